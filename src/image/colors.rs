//! The small per-frame steps around the motion volume's per-pixel colours
//! (`motionblur.methods.motion_volume`): the pixel bounds of the volumes' vertices, their vertex
//! colours sampled from the splatted image, and each pixel's coverage alpha times its splatted
//! colour. Each was a handful of numpy passes over 40k vertices or a window of pixels.
use rayon::prelude::*;

use crate::error::{Error, Result};

/// Points per parallel chunk (fixed: min/max and per-point results need no ordered sums).
const CHUNK: usize = 8192;

/// Below this splatted alpha a pixel's colour is not trusted (`MIN_ALPHA` in Python).
pub const MIN_ALPHA: f32 = 1e-3;

fn check_map(map: &[f64; 16]) -> Result<()> {
    if !map.iter().all(|v| v.is_finite()) {
        return Err(Error::value("map", "contains NaN or inf"));
    }
    Ok(())
}

/// `points` (flat `(n, 3)`) as `n`, checked finite.
fn check_points(points: &[f64]) -> Result<usize> {
    if points.len() % 3 != 0 {
        return Err(Error::shape("points", "expected (N,3) values"));
    }
    if points
        .par_chunks(3 * CHUNK)
        .any(|c| c.iter().any(|v| !v.is_finite()))
    {
        return Err(Error::value("points", "contains NaN or inf"));
    }
    Ok(points.len() / 3)
}

/// Pixel position of `p` under the row-major homogeneous `map` (to `(x w, y w, ., w)`), or
/// None when `w <= 1e-9` (behind the camera).
#[inline(always)]
fn project(map: &[f64; 16], p: &[f64]) -> Option<[f64; 2]> {
    let row = |r: usize| {
        map[4 * r] * p[0] + map[4 * r + 1] * p[1] + map[4 * r + 2] * p[2] + map[4 * r + 3]
    };
    let w = row(3);
    (w > 1e-9).then(|| [row(0) / w, row(1) / w])
}

/// `(x_min, y_min, x_max, y_max)` of the pixel positions of `points` (flat `(n, 3)`) under
/// `map`, or None when a point is behind the camera (none: infinities).
pub fn pixel_bounds(map: &[f64; 16], points: &[f64]) -> Result<Option<[f64; 4]>> {
    check_map(map)?;
    check_points(points)?;
    let none = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    let merge = |a: Option<[f64; 4]>, b: Option<[f64; 4]>| match (a, b) {
        (Some(a), Some(b)) => Some([
            a[0].min(b[0]),
            a[1].min(b[1]),
            a[2].max(b[2]),
            a[3].max(b[3]),
        ]),
        _ => None,
    };
    Ok(points
        .par_chunks(3 * CHUNK)
        .map(|c| {
            c.chunks_exact(3).try_fold(none, |b, p| {
                project(map, p).map(|[x, y]| [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)])
            })
        })
        .reduce(|| Some(none), merge))
}

/// Per point of `points` (flat `(n, 3)`), its `rgba` (flat `(n, 4)`) with the colour replaced by the straight colour of the pixel of the
/// premultiplied `img` (`w` x `h`) it falls in under `map` (the truncated position, clamped to
/// the image), where that pixel's alpha is at least `MIN_ALPHA` (1e-3) and the point is in front of
/// the camera. Returns `(n, 4)` floats.
pub fn sample_colors(
    img: &[f32],
    w: usize,
    h: usize,
    map: &[f64; 16],
    points: &[f64],
    rgba: &[f32],
) -> Result<Vec<f32>> {
    super::check_image("img", img, w, h, 4)?;
    check_map(map)?;
    let n = check_points(points)?;
    if rgba.len() != 4 * n {
        return Err(Error::shape(
            "rgba",
            format!("expected {n} rows like points, got {} values", rgba.len()),
        ));
    }
    let mut out = vec![0.0f32; 4 * n];
    out.par_chunks_mut(4 * CHUNK)
        .zip(points.par_chunks(3 * CHUNK).zip(rgba.par_chunks(4 * CHUNK)))
        .for_each(|(o, (ps, cs))| {
            let each = o
                .chunks_exact_mut(4)
                .zip(ps.chunks_exact(3))
                .zip(cs.chunks_exact(4));
            for ((o, p), c) in each {
                o.copy_from_slice(c);
                let Some([x, y]) = project(map, p) else {
                    continue;
                };
                // numpy's astype(int64) truncates toward zero, then clip
                let i = (x as i64).clamp(0, w as i64 - 1) as usize;
                let j = (y as i64).clamp(0, h as i64 - 1) as usize;
                let s = &img[4 * (j * w + i)..4 * (j * w + i) + 4];
                if s[3] >= MIN_ALPHA {
                    let a = s[3].max(MIN_ALPHA);
                    o[..3].iter_mut().zip(s).for_each(|(o, s)| *o = s / a);
                }
            }
        });
    Ok(out)
}

/// Per pixel: the volumes' coverage alpha `A` (alpha of `rgba`, drawn over nothing) times the
/// splatted colour of `averaged` (`rgb * A / max(a, MIN_ALPHA)`) where its alpha `a` is at least
/// `MIN_ALPHA` (`rgba`'s own colour elsewhere), alpha `A`, plus `(1 - A) under` when `under`
/// is given. All `(n, 4)` premultiplied. Returns `(n, 4)` floats.
pub fn colored(rgba: &[f32], averaged: &[f32], under: Option<&[f32]>) -> Result<Vec<f32>> {
    if averaged.len() != rgba.len() || rgba.len() % 4 != 0 {
        return Err(Error::shape(
            "averaged",
            format!(
                "expected {} values like rgba, got {}",
                rgba.len(),
                averaged.len()
            ),
        ));
    }
    if let Some(u) = under {
        if u.len() != rgba.len() {
            return Err(Error::shape(
                "static_rgba",
                format!("expected {} values like rgba, got {}", rgba.len(), u.len()),
            ));
        }
    }
    let mut out = vec![0.0f32; rgba.len()];
    out.par_chunks_mut(4 * CHUNK)
        .enumerate()
        .for_each(|(k, o)| {
            let at = 4 * CHUNK * k;
            let r = &rgba[at..at + o.len()];
            let s = &averaged[at..at + o.len()];
            let u = under.map(|u| &u[at..at + o.len()]);
            for (px, ((o, r), s)) in o
                .chunks_exact_mut(4)
                .zip(r.chunks_exact(4))
                .zip(s.chunks_exact(4))
                .enumerate()
            {
                let a = r[3];
                if s[3] >= MIN_ALPHA {
                    let f = a / s[3].max(MIN_ALPHA);
                    o[..3].iter_mut().zip(s).for_each(|(o, s)| *o = s * f);
                } else {
                    o[..3].copy_from_slice(&r[..3]);
                }
                o[3] = a;
                if let Some(u) = u {
                    let u = &u[4 * px..4 * px + 4];
                    o.iter_mut().zip(u).for_each(|(o, u)| *o += (1.0 - a) * u);
                }
            }
        });
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pixel (x, y) = (p.x + 2, 3 - p.y) with w = 1 (z = -1 behind).
    const MAP: [f64; 16] = [
        1.0, 0.0, 0.0, 2.0, //
        0.0, -1.0, 0.0, 3.0, //
        0.0, 0.0, 1.0, 0.0, //
        0.0, 0.0, 1.0, 0.0,
    ];

    #[test]
    fn bounds_and_samples() {
        let pts = [0.5, 0.5, 1.0, 1.25, -0.5, 1.0, -1.7, 2.9, 1.0];
        let b = pixel_bounds(&MAP, &pts).unwrap().unwrap();
        for (a, b) in b.iter().zip([0.3, 0.1, 3.25, 3.5]) {
            assert!((a - b).abs() < 1e-12, "{a} {b}");
        }
        assert_eq!(pixel_bounds(&MAP, &[0.0, 0.0, -1.0]).unwrap(), None);
        assert!(pixel_bounds(&MAP, &[f64::NAN, 0.0, 1.0]).is_err());
        // a 4x4 image, pixel (2, 2) red at alpha 0.5, pixel (3, 3) alpha below MIN_ALPHA
        let mut img = vec![0.0f32; 64];
        img[4 * 10..4 * 10 + 4].copy_from_slice(&[0.5, 0.0, 0.0, 0.5]);
        img[4 * 15..4 * 15 + 4].copy_from_slice(&[1e-4, 0.0, 0.0, 1e-4]);
        let pts = [
            [0.5, 0.5, 1.0],
            [1.9, -0.9, 1.0],
            [0.5, 0.5, -1.0],
            [-9.0, 9.0, 1.0],
        ]
        .concat();
        let rgba = [0.0, 0.0, 1.0, 0.25].repeat(4);
        let out = sample_colors(&img, 4, 4, &MAP, &pts, &rgba).unwrap();
        assert_eq!(&out[..4], &[1.0, 0.0, 0.0, 0.25]); // pixel (2, 2)
        assert_eq!(&out[4..8], &[0.0, 0.0, 1.0, 0.25]); // pixel (3, 3): too thin
        assert_eq!(&out[8..12], &[0.0, 0.0, 1.0, 0.25]); // behind
        assert_eq!(&out[12..], &[0.0, 0.0, 1.0, 0.25]); // clamped to (0, 0): empty
        assert!(sample_colors(&img, 4, 4, &MAP, &pts, &rgba[..12]).is_err());
        assert!(sample_colors(&img, 5, 4, &MAP, &pts, &rgba).is_err());
    }

    #[test]
    fn coverage_times_colour_over_under() {
        let rgba = [0.1, 0.2, 0.3, 0.5, 0.1, 0.2, 0.3, 0.5];
        let avg = [0.4, 0.2, 0.0, 0.8, 0.4, 0.2, 0.0, 1e-4];
        let under = [1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0];
        let out = colored(&rgba, &avg, Some(&under)).unwrap();
        let want = [0.25 + 0.5, 0.125 + 0.5, 0.5, 1.0, 0.1, 0.2, 0.3, 0.5];
        for (a, b) in out.iter().zip(want) {
            assert!((a - b).abs() < 1e-6, "{out:?}");
        }
        assert!(colored(&rgba, &avg[..4], None).is_err());
        let one = crate::on_threads(1, || colored(&rgba, &avg, None).unwrap());
        assert_eq!(
            one,
            crate::on_threads(2, || colored(&rgba, &avg, None).unwrap())
        );
    }
}
