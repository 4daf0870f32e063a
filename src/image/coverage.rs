//! The last step of the `opaque_image` method's coverage glow, in one pass over a window: the
//! moving object's box-blurred colour (its opacity capped at 1) composited over the static
//! pixels, and, with layers, the static pixels nearer than the blurred object's mean depth kept
//! in front of it (Kraus 2013, section 4.1's "under").
//!
//! Per pixel of the window, with `b` the blurred colour, `(zm, _, _, m)` the blurred
//! depth-times-mask and mask, `s` the static colour and `z` the static depth:
//!
//! ```text
//! b     = b * (1 / b_a)                  where b_a > 1
//! out   = (1 - b_a) * s + b
//! front = m > 1e-6 and z < zm / max(m, 1e-30)          (with layers)
//! out   = s + (1 - s_a) * b              where front
//! ```
//!
//! in float32, in that order: the bits of the same steps written with numpy arrays (the
//! method's former composite). Rows run in parallel and read only the inputs, so the result does
//! not depend on the thread count.
use rayon::prelude::*;

use super::{filled, put4};
use crate::error::{Error, Result};

/// A window `(y0, y1, x0, x1)` of an image: rows `y0..y1`, columns `x0..x1`.
pub type Window = (usize, usize, usize, usize);

/// One pixel of the composite of the module docs: the blurred colour `b`, the static colour
/// `s` and, with layers, `(zm, m, z)` (the blurred depth-times-mask and mask, the static
/// depth). Returns the pixel and whether the static pixel was kept in front.
#[inline(always)]
pub(crate) fn composite_pixel(
    mut b: [f32; 4],
    s: [f32; 4],
    layers: Option<(f32, f32, f32)>,
) -> ([f32; 4], bool) {
    if b[3] > 1.0 {
        let r = 1.0 / b[3];
        b = b.map(|v| v * r);
    }
    let mut o = [0.0f32; 4];
    for k in 0..4 {
        o[k] = (1.0 - b[3]) * s[k] + b[k];
    }
    if let Some((zm, m, z)) = layers {
        // (m > 1e-6 is false for NaN, as numpy's; then m is no NaN and the max below is
        // numpy's maximum)
        if m > 1e-6 {
            let zbar = zm / if m > 1e-30 { m } else { 1e-30 };
            if z < zbar {
                for k in 0..4 {
                    o[k] = s[k] + (1.0 - s[3]) * b[k];
                }
                return (o, true);
            }
        }
    }
    (o, false)
}

/// The composite of the module docs over `window` of the `w` x `h` static colour `back`
/// (`(h, w, 4)`) and depth `back_depth` (`(h, w)`): `blurred` and `depth` are `(y1 - y0, x1 -
/// x0, 4)`. Returns the window's colour and the number of pixels kept in front (0 without
/// `layers`).
pub fn coverage_composite(
    (back, back_depth): (&[f32], &[f32]),
    (w, h): (usize, usize),
    window: Window,
    (blurred, depth): (&[f32], &[f32]),
    layers: bool,
) -> Result<(Vec<f32>, u64)> {
    let (y0, y1, x0, x1) = window;
    if back.len() != w * h * 4 {
        return Err(Error::shape("back", format!("expected ({h},{w},4) values")));
    }
    if back_depth.len() != w * h {
        return Err(Error::shape(
            "back_depth",
            format!("expected ({h},{w}) values"),
        ));
    }
    if !(y0 < y1 && y1 <= h && x0 < x1 && x1 <= w) {
        return Err(Error::value(
            "window",
            format!("({y0}, {y1}, {x0}, {x1}) is not a non-empty window of {w}x{h} pixels"),
        ));
    }
    let (ww, wh) = (x1 - x0, y1 - y0);
    for (name, a) in [("blurred", blurred), ("depth", depth)] {
        if a.len() != ww * wh * 4 {
            return Err(Error::shape(name, format!("expected ({wh},{ww},4) values")));
        }
    }
    let mut front = 0u64;
    let out = filled(ww * wh * 4, |out| {
        front = out
            .par_chunks_mut(ww * 4)
            .enumerate()
            .map(|(r, row)| {
                let y = y0 + r;
                let mut front = 0u64;
                for c in 0..ww {
                    let i = (r * ww + c) * 4;
                    let j = y * w + x0 + c;
                    let b: [f32; 4] = blurred[i..i + 4].try_into().expect("four channels");
                    let s: [f32; 4] = back[j * 4..j * 4 + 4].try_into().expect("four channels");
                    let z = layers.then(|| (depth[i], depth[i + 3], back_depth[j]));
                    let (o, near) = composite_pixel(b, s, z);
                    front += near as u64;
                    put4(row, c, o);
                }
                front
            })
            .sum();
    });
    Ok((out, front))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The composite pixel by pixel, serial, as the module docs write it.
    fn serial(
        back: &[f32],
        zb: &[f32],
        w: usize,
        (y0, y1, x0, x1): Window,
        blurred: &[f32],
        depth: &[f32],
        layers: bool,
    ) -> (Vec<f32>, u64) {
        let ww = x1 - x0;
        let mut out = vec![0.0f32; (y1 - y0) * ww * 4];
        let mut front = 0;
        for y in y0..y1 {
            for x in x0..x1 {
                let i = ((y - y0) * ww + x - x0) * 4;
                let j = y * w + x;
                let mut b = [0.0f32; 4];
                b.copy_from_slice(&blurred[i..i + 4]);
                if b[3] > 1.0 {
                    let s = 1.0 / b[3];
                    for v in &mut b {
                        *v *= s;
                    }
                }
                let s = &back[j * 4..j * 4 + 4];
                let m = depth[i + 3];
                let near = layers && m > 1e-6 && zb[j] < depth[i] / m.max(1e-30);
                front += near as u64;
                for k in 0..4 {
                    out[i + k] = if near {
                        s[k] + (1.0 - s[3]) * b[k]
                    } else {
                        (1.0 - b[3]) * s[k] + b[k]
                    };
                }
            }
        }
        (out, front)
    }

    #[test]
    fn matches_the_serial_composite_on_any_thread_count() {
        let (w, h) = (37, 23);
        let win = (3, 20, 5, 33);
        let (ww, wh) = (28, 17);
        let back: Vec<f32> = (0..w * h * 4)
            .map(|i| ((i * 7919) % 997) as f32 / 997.0)
            .collect();
        let zb: Vec<f32> = (0..w * h)
            .map(|i| {
                if i % 11 == 0 {
                    f32::INFINITY
                } else {
                    1.0 + (i % 13) as f32 * 0.3
                }
            })
            .collect();
        // blurred alphas from 0 to 1.5 (capped), masks from 0 (no reach) to 1
        let blurred: Vec<f32> = (0..ww * wh * 4)
            .map(|i| ((i * 104_729) % 1499) as f32 / 1000.0)
            .collect();
        let depth: Vec<f32> = (0..ww * wh * 4)
            .map(|i| match i % 4 {
                0 => ((i * 31) % 17) as f32 * 0.2,
                3 => ((i * 13) % 5) as f32 * 0.25,
                _ => 0.0,
            })
            .collect();
        for layers in [false, true] {
            let run = || coverage_composite((&back, &zb), (w, h), win, (&blurred, &depth), layers);
            let (a, fa) = run().unwrap();
            let (b, fb) = crate::on_threads(1, run).unwrap();
            let (c, fc) = serial(&back, &zb, w, win, &blurred, &depth, layers);
            assert!(a.iter().zip(&c).all(|(p, q)| p.to_bits() == q.to_bits()));
            assert!(a.iter().zip(&b).all(|(p, q)| p.to_bits() == q.to_bits()));
            assert_eq!((fa, fb), (fc, fc));
            assert_eq!(fc > 0, layers, "the data has pixels in front with layers");
        }
    }

    #[test]
    fn bad_windows_and_shapes_are_errors() {
        let (back, zb) = (vec![0.0f32; 4 * 6 * 4], vec![1.0f32; 4 * 6]);
        let b = vec![0.0f32; 2 * 2 * 4];
        let ok = coverage_composite((&back, &zb), (6, 4), (1, 3, 2, 4), (&b, &b), true);
        assert!(ok.is_ok());
        for win in [(1, 1, 2, 4), (3, 5, 2, 4), (1, 3, 5, 7)] {
            let e = coverage_composite((&back, &zb), (6, 4), win, (&b, &b), true).unwrap_err();
            assert!(e.to_string().contains("window"), "{e}");
        }
        let e = coverage_composite((&back, &zb), (6, 4), (0, 3, 2, 4), (&b, &b), true).unwrap_err();
        assert!(e.to_string().contains("blurred"), "{e}");
    }
}
