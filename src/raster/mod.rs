//! The CPU rasterizer: camera, clipping, triangle setup, tiles, blending, buffers.
