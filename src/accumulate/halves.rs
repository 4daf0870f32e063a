//! The two halves of an accumulation (its even and its odd time samples, each summed apart)
//! made into the frame and the difference its error estimate reads, over the window the
//! samples drew in, in one pass.
//!
//! Each part is a weighted mean of some samples (`mass`, the shutter weight they carry): its
//! pixels are a `base` image (the static layer, or a whole frame) with the `drawn` pixels of
//! its own window in place. Per pixel and channel, in float64, each half is
//! `(0 + m_1 v_1 + m_2 v_2 + ...) / M` (`v_i` its parts' values in order, `M` their masses
//! summed from 0 in order); the difference `d = a - b` composited over a background `pre`
//! (premultiplied) is `d_k + (-d_alpha) pre_k`; the frame is `(a M_a + b M_b) / (M_a + M_b)`
//! rounded to float32. These are numpy's operations in `HalfSums.frame`'s order, so the bits
//! are those of that numpy code (tests/methods/test_accumulation_frame.py compares them).
use crate::error::{Error, Result};

/// One part of a half: its samples' weighted mean over the image.
#[derive(Clone, Copy, Debug)]
pub struct HalfPart<'a> {
    /// 0 for the even half, 1 for the odd one.
    pub half: usize,
    /// The shutter weight of its samples (its weight in the half's mean).
    pub mass: f64,
    /// `(H, W, 4)` premultiplied RGBA: the pixels outside `window`.
    pub base: &'a [f32],
    /// `(x0, y0, x1, y1)` of the image the part drew in, with its `drawn` pixels.
    pub window: Option<([usize; 4], &'a [f32])>,
}

/// The frame's window and the halves' composited difference there (see the module docs).
#[derive(Clone, Debug)]
pub struct Halves {
    /// `(h, w, 4)` float64: `a - b` composited over the background.
    pub difference: Vec<f64>,
    /// `(h, w, 4)` float32: the frame, both halves by their masses.
    pub frame: Vec<f32>,
    /// The masses of the even and the odd half.
    pub masses: [f64; 2],
}

/// The halves of `parts` over `window` (`x0, y0, x1, y1`) of a `width` x `height` image,
/// their difference composited over `pre` (premultiplied RGBA) and the frame.
pub fn halves(
    parts: &[HalfPart<'_>],
    (width, height): (usize, usize),
    window: [usize; 4],
    pre: [f64; 4],
) -> Result<Halves> {
    let [x0, y0, x1, y1] = window;
    if !(x0 < x1 && y0 < y1 && x1 <= width && y1 <= height) {
        return Err(Error::value(
            "window",
            "must be a non-empty rectangle of the image",
        ));
    }
    for p in parts {
        check_part(p, (width, height))?;
    }
    let mut masses = [0.0f64; 2];
    for p in parts {
        masses[p.half] += p.mass;
    }
    let (w, h) = (x1 - x0, y1 - y0);
    let mut difference = vec![0.0f64; w * h * 4];
    let mut frame = vec![0.0f32; w * h * 4];
    let row = |(y, (diff, out)): (usize, (&mut [f64], &mut [f32]))| {
        for (i, x) in (x0..x1).enumerate() {
            let (d, f) = pixel(parts, masses, pre, width, (x, y0 + y));
            diff[i * 4..i * 4 + 4].copy_from_slice(&d);
            out[i * 4..i * 4 + 4].copy_from_slice(&f);
        }
    };
    let rows = difference.chunks_mut(w * 4).zip(frame.chunks_mut(w * 4));
    if w * h < SERIAL_PIXELS {
        rows.enumerate().for_each(row);
    } else {
        use rayon::prelude::*;
        difference
            .par_chunks_mut(w * 4)
            .zip(frame.par_chunks_mut(w * 4))
            .enumerate()
            .for_each(row);
    }
    Ok(Halves {
        difference,
        frame,
        masses,
    })
}

/// Windows of fewer pixels are made on the calling thread (no pool: a hand-off to it costs
/// more than such a window); larger ones row by row in parallel (the same bits: each pixel
/// is its own).
pub const SERIAL_PIXELS: usize = 1 << 16;

/// Pixel `(x, y)`'s composited difference and frame value (the module docs' operations).
#[inline]
fn pixel(
    parts: &[HalfPart<'_>],
    masses: [f64; 2],
    pre: [f64; 4],
    width: usize,
    (x, y): (usize, usize),
) -> ([f64; 4], [f32; 4]) {
    let mut sums = [[0.0f64; 4]; 2];
    for p in parts {
        let v = value(p, width, (x, y));
        for (s, v) in sums[p.half].iter_mut().zip(v) {
            *s += f64::from(*v) * p.mass;
        }
    }
    let a = sums[0].map(|s| s / masses[0]);
    let b = sums[1].map(|s| s / masses[1]);
    let d: [f64; 4] = std::array::from_fn(|k| a[k] - b[k]);
    let scale = -d[3];
    let total = masses[0] + masses[1];
    (
        std::array::from_fn(|k| d[k] + scale * pre[k]),
        std::array::from_fn(|k| ((a[k] * masses[0] + b[k] * masses[1]) / total) as f32),
    )
}

/// Pixel `(x, y)` of a part: its drawn value inside its window, its base's outside.
#[inline]
fn value<'a>(p: &HalfPart<'a>, width: usize, (x, y): (usize, usize)) -> &'a [f32] {
    if let Some(([wx0, wy0, wx1, wy1], drawn)) = p.window {
        if (wx0..wx1).contains(&x) && (wy0..wy1).contains(&y) {
            let i = ((y - wy0) * (wx1 - wx0) + (x - wx0)) * 4;
            return &drawn[i..i + 4];
        }
    }
    let i = (y * width + x) * 4;
    &p.base[i..i + 4]
}

/// A part's half is 0 or 1, its base the image's size, its window inside the image and its
/// drawn pixels the window's size.
fn check_part(p: &HalfPart<'_>, (width, height): (usize, usize)) -> Result<()> {
    if p.half > 1 {
        return Err(Error::value("half", "must be 0 or 1"));
    }
    if p.base.len() != width * height * 4 {
        return Err(Error::shape("base", "must be (H, W, 4) of the image"));
    }
    if let Some(([x0, y0, x1, y1], drawn)) = p.window {
        if !(x0 <= x1 && y0 <= y1 && x1 <= width && y1 <= height) {
            return Err(Error::value("window", "must lie inside the image"));
        }
        if drawn.len() != (x1 - x0) * (y1 - y0) * 4 {
            return Err(Error::shape("drawn", "must be (y1 - y0, x1 - x0, 4)"));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_parts_a_half_give_their_weighted_means() {
        // a 3 x 2 image; half 0: one part of mass 0.5 drawing pixel (1, 0); half 1: two parts
        // of masses 0.25 and 0.25, the second drawing pixel (2, 1)
        let base: Vec<f32> = (0..24).map(|i| i as f32 / 24.0).collect();
        let d0 = [1.0f32, 0.5, 0.25, 1.0];
        let d1 = [0.0f32, 0.0, 1.0, 0.5];
        let parts = [
            HalfPart {
                half: 0,
                mass: 0.5,
                base: &base,
                window: Some(([1, 0, 2, 1], &d0)),
            },
            HalfPart {
                half: 1,
                mass: 0.25,
                base: &base,
                window: None,
            },
            HalfPart {
                half: 1,
                mass: 0.25,
                base: &base,
                window: Some(([2, 1, 3, 2], &d1)),
            },
        ];
        let pre = [0.1, 0.2, 0.3, 1.0];
        let out = halves(&parts, (3, 2), [0, 0, 3, 2], pre).unwrap();
        assert_eq!(out.masses, [0.5, 0.5]);
        for y in 0..2 {
            for x in 0..3 {
                let i = (y * 3 + x) * 4;
                let base = |k: usize| f64::from(base[i + k]);
                let a: [f64; 4] = std::array::from_fn(|k| {
                    if (x, y) == (1, 0) {
                        f64::from(d0[k])
                    } else {
                        base(k)
                    }
                });
                let b: [f64; 4] = std::array::from_fn(|k| {
                    let second = if (x, y) == (2, 1) {
                        f64::from(d1[k])
                    } else {
                        base(k)
                    };
                    (base(k) * 0.25 + second * 0.25) / 0.5
                });
                for k in 0..4 {
                    let d = a[k] - b[k] - (a[3] - b[3]) * pre[k];
                    assert!((out.difference[i + k] - d).abs() < 1e-12, "({x}, {y}) {k}");
                    let f = ((a[k] + b[k]) / 2.0) as f32;
                    assert!((out.frame[i + k] - f).abs() <= 1e-6, "({x}, {y}) {k}");
                }
            }
        }
    }

    #[test]
    fn bad_parts_name_what_is_wrong() {
        let base = vec![0.0f32; 24];
        let drawn = vec![0.0f32; 4];
        let part = |half, window| HalfPart {
            half,
            mass: 1.0,
            base: &base,
            window,
        };
        let err = |parts: &[HalfPart<'_>], win| {
            halves(parts, (3, 2), win, [0.0; 4])
                .unwrap_err()
                .to_string()
        };
        assert!(err(&[part(2, None)], [0, 0, 3, 2]).contains("half"));
        assert!(err(&[part(0, Some(([0, 0, 2, 1], &drawn)))], [0, 0, 3, 2]).contains("drawn"));
        assert!(err(&[part(0, Some(([0, 0, 4, 1], &drawn)))], [0, 0, 3, 2]).contains("window"));
        assert!(err(&[part(0, None)], [0, 0, 3, 3]).contains("window"));
        let short = vec![0.0f32; 20];
        let p = HalfPart {
            half: 0,
            mass: 1.0,
            base: &short,
            window: None,
        };
        assert!(err(&[p], [0, 0, 3, 2]).contains("base"));
    }
}
