//! Image-space blur kernels: box and directional blur, glow, opaque blur, pyramids, depth of field, camera blur.
