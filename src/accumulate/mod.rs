//! The accumulation buffer: its kernels (the weighted, depth-tested sum of a moving layer, the
//! composite and resolve of layers), the conservative back-face selection of a translating
//! mesh, the painter that draws objects at any shutter time, the whole frame's samples in
//! one call, and the frame and error difference of its two halves.
mod facing;
mod frame;
mod halves;
mod kernels;
mod painter;

pub use facing::facing_faces;
pub use frame::{
    accumulate_moving, accumulate_still, accumulate_still_parts, pixel_rect, sample_rects,
    window_projection, Accumulated, Samples, StillCamera,
};
pub use halves::{halves, HalfPart, Halves, SERIAL_PIXELS};
pub use kernels::{accumulate, composite, over, resolve, BuffersMut, Rect};
pub use painter::{PaintObject, Painter};
