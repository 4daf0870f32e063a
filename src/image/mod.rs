//! Image-space blur kernels: box and directional blur, glow, opaque blur, pyramids, depth of field,
//! camera blur (Kraus 2013, "Using opaque image blur..."; Chapman 2011, camera motion blur), and
//! splatting along per-source image paths (`splat`).
//!
//! Conventions: images are row-major float32, `(h, w, 4)` premultiplied RGBA or `(h, w)` single
//! channel, row 0 at the top. Outside the image everything is transparent black (zero), so a
//! blur near the border fades to transparent and the opaque blur's rescale (eq. 7) restores the
//! colour there: the result does not depend on the size of the viewport.
//!
//! Every kernel works on rows in parallel (rayon) with no cross-row reduction, so the result is
//! bit-identical for any thread count. Directional filters run on the "major axis" of their
//! direction: a mostly vertical direction is handled by transposing the image, and an oblique
//! one by shearing the image so that the direction becomes a row (see `lines`).

mod boxblur;
mod camera;
mod camera_line;
mod colors;
mod coverage;
mod coverage_blur;
mod coverage_cut;
mod coverage_oblique;
mod dof;
mod glow;
mod lens;
mod lines;
mod object_pixels;
mod opaque;
mod opaque_row;
mod pool;
mod pyramid;
mod reach;
mod reconstruct;
mod scatter;
mod sheared_finish;
mod sheared_row;
mod splat;
mod velocity_groups;

pub use boxblur::box_blur;
pub use camera::{
    camera_frame_blur, camera_motion_blur, camera_velocity, velocity_blur, CameraBlur,
    CameraMatrices, FrameMotion, MAX_FPS_RATIO, MAX_SAMPLES, MAX_VELOCITY,
};
pub use colors::{colored, pixel_bounds, sample_colors, MIN_ALPHA};
pub use coverage::coverage_composite;
pub use coverage_blur::coverage_blur;
pub use coverage_cut::{CoverageObject, CoveragePart, CoverageSource};
pub use dof::{depth_of_field, DofParams, MAX_LAYERS};
pub use glow::glow;
pub use lens::{lens_blur, LensParams, MAX_LENS_LEVELS};
pub use object_pixels::{object_pixels, ObjectPixels};
pub use opaque::{opaque_blur, opaque_motion_blur, opaque_motion_blur_into};
pub use opaque_row::Composite;
pub use pyramid::{pyramid_blur, pyramid_glow, pyramid_opaque_blur, MAX_LEVELS};
pub use reconstruct::{
    max_speed, max_speed_in, reconstruct, reconstruct_moving, ReconstructParams, MAX_TAPS,
};
pub use scatter::{scatter_pieces, Piece};
pub use splat::splat_paths;
pub use velocity_groups::one_velocity_group;

use crate::budget::Need;
use crate::error::{Error, Result};

/// Copies of its input an image kernel holds at most (transposed and sheared rows, the
/// pyramid's levels, a third more, and its expansions, the depth of field's layer and sum),
/// counted against the memory budget by [`check_image`].
const IMAGE_COPIES: u64 = 8;

/// Largest accepted filter length (pixels); longer filters are absurd for any image we accept.
pub const MAX_LENGTH: f32 = 65536.0;

/// Below this blurred opacity the rescale of eq. 7 treats the pixel as empty (colour 0).
pub const ALPHA_EPS: f32 = 1e-12;

/// Whether the kernels run their vector forms (`crate::simd`): the same bits as the plain ones.
#[inline]
pub(crate) fn simd() -> bool {
    crate::simd::simd_enabled()
}

/// Checks that `data` holds `h * w * channels` values, that the image is not empty, and that
/// a kernel holding [`IMAGE_COPIES`] copies of it fits the memory budget.
pub(crate) fn check_image(
    name: &'static str,
    data: &[f32],
    w: usize,
    h: usize,
    channels: usize,
) -> Result<()> {
    if w == 0 || h == 0 {
        return Err(Error::shape(name, format!("is empty ({h}x{w})")));
    }
    if data.len() != w * h * channels {
        return Err(Error::shape(
            name,
            format!(
                "expected {} values for ({h},{w},{channels}), got {}",
                w * h * channels,
                data.len()
            ),
        ));
    }
    Need::new("an image kernel (8 copies of its input at most)")
        .add(
            &[
                ("width", w as u64),
                ("height", h as u64),
                ("channels", channels as u64),
            ],
            4 * IMAGE_COPIES,
        )?
        .check()
}

/// Checks the `buffers` images of `w` x `h` RGBA pixels (float32) that splatting sums (one per
/// run of sources, and the result) against the memory budget.
pub(crate) fn check_splat_buffers(
    call: &'static str,
    w: usize,
    h: usize,
    buffers: usize,
) -> Result<()> {
    Need::new(call)
        .add(
            &[
                ("width", w as u64),
                ("height", h as u64),
                ("buffers", buffers as u64 + 1),
            ],
            16,
        )?
        .check()
}

/// Fails naming `name` when any value is NaN or infinite (in parallel over rows).
pub(crate) fn check_finite(name: &'static str, data: &[f32]) -> Result<()> {
    use rayon::prelude::*;
    let bad = data
        .par_chunks(1 << 16)
        .any(|c| c.iter().fold(false, |b, v| b | !v.is_finite()));
    if bad {
        return Err(Error::value(name, "contains NaN or inf"));
    }
    Ok(())
}

/// Whether an alpha is outside [0, 1] (NaN included; -0.0 is inside), from its bits: the
/// bits of a float in [+0, 1] are at most those of 1.0, and -0.0 is the only negative inside.
#[inline]
pub(crate) fn alpha_out_of_range(bits: u32) -> bool {
    bits > 0x3f80_0000 && bits != 0x8000_0000
}

/// Fails naming `name` when any value is NaN or infinite, or when an alpha (every value of a
/// one-channel image, the last of each pixel of a four-channel one) is outside [0, 1]: the
/// opaque blurs, glows and composites are defined for premultiplied colour with such alphas
/// only (one parallel pass).
pub(crate) fn check_premultiplied(name: &'static str, data: &[f32], channels: usize) -> Result<()> {
    use rayon::prelude::*;
    check_finite(name, data)?;
    let bad = data
        .par_chunks(channels << 14)
        .flat_map_iter(|c| c.iter().skip(channels - 1).step_by(channels))
        .find_first(|a| alpha_out_of_range(a.to_bits()));
    if let Some(a) = bad {
        return Err(Error::value(
            name,
            format!(
                "alpha must be in [0, 1] (premultiplied colour), got {a}; an opaque blur, glow or \
                 composite of other alphas is undefined"
            ),
        ));
    }
    Ok(())
}

/// Checks a direction and a length: finite, length in [0, MAX_LENGTH].
pub(crate) fn check_direction(
    direction: [f32; 2],
    length: f32,
    len_name: &'static str,
) -> Result<()> {
    if !direction.iter().all(|v| v.is_finite()) {
        return Err(Error::value("direction", "must be finite"));
    }
    if !length.is_finite() || !(0.0..=MAX_LENGTH).contains(&length) {
        return Err(Error::value(
            len_name,
            format!("must be finite and in [0, {MAX_LENGTH}], got {length}"),
        ));
    }
    Ok(())
}

/// An output buffer of `n` floats that `fill` writes completely (every element, before any
/// read). It is not zeroed first: for a full-size image, zeroing costs as much as a blur's own
/// write pass.
pub(crate) fn filled(n: usize, fill: impl FnOnce(&mut [std::mem::MaybeUninit<f32>])) -> Vec<f32> {
    filled_with(n, fill)
}

/// [`filled`] into a buffer from [`pool`] when it has one (its pages already in memory),
/// else a new one.
pub(crate) fn pooled(n: usize, fill: impl FnOnce(&mut [std::mem::MaybeUninit<f32>])) -> Vec<f32> {
    match pool::reuse(n) {
        Some(mut v) => {
            // SAFETY: f32 and MaybeUninit<f32> share their layout; `fill` writes every element
            // (its contract), over values that were initialised anyway.
            let u = unsafe {
                std::slice::from_raw_parts_mut(v.as_mut_ptr() as *mut std::mem::MaybeUninit<f32>, n)
            };
            fill(u);
            v
        }
        None => filled(n, fill),
    }
}

/// [`filled`] for any plain type `T` (floats, pairs of floats). A large buffer is backed by
/// huge pages ([`crate::budget::advise_huge_pages`]) before `fill` first touches it.
pub(crate) fn filled_with<T: Copy>(
    n: usize,
    fill: impl FnOnce(&mut [std::mem::MaybeUninit<T>]),
) -> Vec<T> {
    let mut v: Vec<std::mem::MaybeUninit<T>> = Vec::with_capacity(n);
    crate::budget::advise_huge_pages(&v);
    // SAFETY: MaybeUninit needs no initialisation.
    unsafe { v.set_len(n) };
    fill(&mut v);
    let mut v = std::mem::ManuallyDrop::new(v);
    // SAFETY: `fill` initialised every element (its contract); MaybeUninit<T> has the layout
    // of T, and the allocation is handed over unchanged.
    unsafe { Vec::from_raw_parts(v.as_mut_ptr() as *mut T, v.len(), v.capacity()) }
}

/// Copies `src` into the uninitialised `dst` (of the same length), as one memcpy.
#[inline]
pub(crate) fn write_copy(dst: &mut [std::mem::MaybeUninit<f32>], src: &[f32]) {
    assert_eq!(dst.len(), src.len());
    // SAFETY: both slices hold `src.len()` f32-sized values (MaybeUninit<f32> has f32's
    // layout) and cannot overlap (one is borrowed mutably).
    unsafe { std::ptr::copy_nonoverlapping(src.as_ptr(), dst.as_mut_ptr() as *mut f32, src.len()) };
}

/// Writes four floats at pixel `x` of an uninitialised `(n, 4)` row.
#[inline(always)]
pub(crate) fn put4(o: &mut [std::mem::MaybeUninit<f32>], x: usize, v: [f32; 4]) {
    for (d, s) in o[x * 4..x * 4 + 4].iter_mut().zip(v) {
        d.write(s);
    }
}

/// Transposes a `(h, w, C)` image into `(w, h, C)`, in cache blocks, in parallel over output rows.
pub(crate) fn transpose<const C: usize>(src: &[f32], w: usize, h: usize) -> Vec<f32> {
    use rayon::prelude::*;
    const B: usize = 32;
    pooled(src.len(), |out| {
        out.par_chunks_mut(B * h * C)
            .enumerate()
            .for_each(|(bx, block)| {
                // block = output rows x in [bx*B, bx*B + B) (output row x has h pixels); every
                // element of it is written once, for each dx < nx and y < h.
                let x0 = bx * B;
                let nx = block.len() / (h * C);
                for y0 in (0..h).step_by(B) {
                    let y1 = (y0 + B).min(h);
                    for y in y0..y1 {
                        let srow = &src[(y * w + x0) * C..(y * w + x0 + nx) * C];
                        for dx in 0..nx {
                            let o = (dx * h + y) * C;
                            write_copy(&mut block[o..o + C], &srow[dx * C..dx * C + C]);
                        }
                    }
                }
            })
    })
}

#[cfg(test)]
mod tests;
