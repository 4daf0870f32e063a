//! Box blur along a direction: running sums along rows (O(1) per pixel, whatever the length).
//!
//! A box of `length` pixels along `direction` averages `2r + 1` taps one major-axis pixel apart,
//! `r = floor(length * c / 2)` where `c = max(|dx|, |dy|) / |direction|` (so an axis-aligned box
//! has exactly `2r + 1 >= length` integer taps). Along an image axis the taps are whole pixels;
//! along any other direction the image is sheared so the taps become a row (see `lines`).
//! Outside the image the taps read transparent black.
use super::lines::{directional_at, plan, Live};
use super::{check_direction, check_finite, check_image};
use crate::error::Result;

/// Calls `emit(x, mean)` for every pixel of a `(n, 4)` row: the mean of the `2r + 1` pixels
/// `x - r ..= x + r` (zero outside). Sums run in f64, so the error does not grow along the row.
#[inline(always)]
pub(crate) fn box_row_each(src: &[f32], n: usize, r: usize, emit: impl FnMut(usize, [f32; 4])) {
    box_row_range(src, n, r, 0, n, emit)
}

/// `box_row_each` for the pixels `xa .. xb` only.
#[inline(always)]
pub(crate) fn box_row_range(
    src: &[f32],
    n: usize,
    r: usize,
    xa: usize,
    xb: usize,
    mut emit: impl FnMut(usize, [f32; 4]),
) {
    debug_assert_eq!(src.len(), n * 4);
    let inv = 1.0 / (2 * r + 1) as f64;
    let px = |i: usize| -> [f64; 4] {
        let p = &src[i * 4..i * 4 + 4];
        [p[0] as f64, p[1] as f64, p[2] as f64, p[3] as f64]
    };
    let mut s = [0.0f64; 4];
    for i in xa.saturating_sub(r)..=(xa + r).min(n - 1) {
        let p = px(i);
        for c in 0..4 {
            s[c] += p[c];
        }
    }
    for x in xa..xb {
        emit(
            x,
            [
                (s[0] * inv) as f32,
                (s[1] * inv) as f32,
                (s[2] * inv) as f32,
                (s[3] * inv) as f32,
            ],
        );
        let a = x + r + 1;
        if a < n {
            let p = px(a);
            for c in 0..4 {
                s[c] += p[c];
            }
        }
        if x >= r {
            let p = px(x - r);
            for c in 0..4 {
                s[c] -= p[c];
            }
        }
    }
}

/// Box blur of a `(h, w, 4)` image along `direction` over `length` pixels (module docs).
/// A zero direction or `r = 0` returns the image unchanged.
pub fn box_blur(
    rgba: &[f32],
    w: usize,
    h: usize,
    direction: [f32; 2],
    length: f32,
) -> Result<Vec<f32>> {
    box_blur_where(rgba, w, h, direction, length, Live::All)
}

fn box_blur_where(
    rgba: &[f32],
    w: usize,
    h: usize,
    direction: [f32; 2],
    length: f32,
    live: Live<'_>,
) -> Result<Vec<f32>> {
    check_image("rgba", rgba, w, h, 4)?;
    check_direction(direction, length, "length")?;
    check_finite("rgba", rgba)?;
    let Some(p) = plan(direction, length * 0.5) else {
        return Ok(rgba.to_vec());
    };
    directional_at::<4, 4, ()>("rgba", rgba, w, h, &p, 0.0, live, box_filter(p.radius))
}

/// The row filter of a box blur with `radius` taps each side (`box_row_each` into the output
/// row), as the line filters take it.
pub(crate) fn box_filter(
    radius: usize,
) -> impl Fn(&[f32], usize, &mut [f32], &mut ()) -> bool + Sync + Send {
    move |src, n, out, _| {
        box_row_each(src, n, radius, |x, m| {
            out[x * 4..x * 4 + 4].copy_from_slice(&m)
        });
        true
    }
}
