//! Accumulation-buffer kernels: the per-sample weighted, depth-tested sum of a moving layer and
//! the one composite over the static layer after the last sample.
//!
//! Layers are row-major `rgba` (N*4 floats, premultiplied) and `depth` (N floats, `inf` where
//! empty). Every output element depends on the same input elements only, so the result does not
//! depend on the thread count.
use rayon::prelude::*;

use crate::error::{Error, Result};

/// Fewest samples per parallel job of `accumulate` (a small rectangle is summed on one thread).
const MIN_SAMPLES: usize = 16384;

/// Samples per parallel job of `over`.
const CHUNK: usize = 8192;

/// A rectangle of samples inside a larger row-major buffer: `width` x `height` samples whose
/// first one is at `(x0, y0)` of a buffer `stride` samples wide.
#[derive(Clone, Copy, Debug)]
pub struct Rect {
    /// Column of the rectangle's first sample.
    pub x0: usize,
    /// Row of the rectangle's first sample.
    pub y0: usize,
    /// Samples per row of the rectangle.
    pub width: usize,
    /// Rows of the rectangle.
    pub height: usize,
    /// Samples per row of the whole buffer.
    pub stride: usize,
}

impl Rect {
    /// The whole buffer of `n` samples as one row.
    pub fn whole(n: usize) -> Self {
        Rect {
            x0: 0,
            y0: 0,
            width: n,
            height: 1,
            stride: n,
        }
    }
}

/// `acc[rect] += weight * rgba` where `depth < limit[rect]` (everywhere when `limit` is None):
/// the moving layer's samples in front of the static surface. `rgba` (4 per sample) and `depth`
/// cover the rectangle only; `acc` (4 per sample) and `limit` the whole buffer.
pub fn accumulate(
    acc: &mut [f32],
    rgba: &[f32],
    depth: &[f32],
    limit: Option<&[f32]>,
    weight: f32,
    rect: Rect,
) -> Result<()> {
    let whole_rows = rect.stride > 0 && acc.len() % (4 * rect.stride) == 0;
    if let (Some(l), true) = (limit, whole_rows) {
        let rows = acc.len() / (4 * rect.stride);
        if l.len() != rows * rect.stride {
            return Err(Error::shape(
                "limit",
                "must have one depth per sample of acc",
            ));
        }
    }
    let limit = limit.map(|data| Limit {
        data,
        stride: rect.stride,
        x0: 0,
        y0: 0,
    });
    accumulate_limited(acc, rgba, depth, limit, weight, rect)
}

/// A depth buffer read at an offset: sample `(x, y)` of `acc` is `data[(y0 + y) * stride + x0 + x]`
/// (a window's limit inside a larger crop).
#[derive(Clone, Copy, Debug)]
pub struct Limit<'a> {
    /// The depths, `stride` a row.
    pub data: &'a [f32],
    /// Samples per row of `data`.
    pub stride: usize,
    /// Column of `data` under `acc`'s first column.
    pub x0: usize,
    /// Row of `data` under `acc`'s first row.
    pub y0: usize,
}

/// [`accumulate`] with the limit read through a [`Limit`] view.
pub fn accumulate_limited(
    acc: &mut [f32],
    rgba: &[f32],
    depth: &[f32],
    limit: Option<Limit<'_>>,
    weight: f32,
    rect: Rect,
) -> Result<()> {
    let n = rect.width * rect.height;
    if rgba.len() != 4 * n || depth.len() != n {
        return Err(Error::shape(
            "rgba",
            "rgba (h,w,4) and depth (h,w) must cover the rectangle",
        ));
    }
    if rect.x0 + rect.width > rect.stride || acc.len() % (4 * rect.stride) != 0 {
        return Err(Error::shape("acc", "the rectangle must lie inside acc"));
    }
    let rows = acc.len() / (4 * rect.stride);
    if rect.y0 + rect.height > rows {
        return Err(Error::shape("acc", "the rectangle must lie inside acc"));
    }
    if let Some(l) = limit {
        if l.x0 + rect.stride > l.stride || (l.y0 + rows) * l.stride > l.data.len() {
            return Err(Error::shape(
                "limit",
                "must have one depth per sample of acc",
            ));
        }
    }
    if !weight.is_finite() {
        return Err(Error::value("weight", "must be finite"));
    }
    if n == 0 {
        return Ok(());
    }
    acc.par_chunks_mut(4 * rect.stride)
        .enumerate()
        .skip(rect.y0)
        .take(rect.height)
        .with_min_len(MIN_SAMPLES.div_ceil(rect.width))
        .for_each(|(y, row)| {
            let ry = y - rect.y0;
            let src = &rgba[4 * ry * rect.width..4 * (ry + 1) * rect.width];
            let dst = &mut row[4 * rect.x0..4 * (rect.x0 + rect.width)];
            let Some(l) = limit else {
                for (a, r) in dst.iter_mut().zip(src) {
                    *a += weight * *r;
                }
                return;
            };
            let dep = &depth[ry * rect.width..(ry + 1) * rect.width];
            let at = (l.y0 + y) * l.stride + l.x0 + rect.x0;
            let lim = &l.data[at..at + rect.width];
            for ((a4, r4), (d, m)) in dst
                .chunks_exact_mut(4)
                .zip(src.chunks_exact(4))
                .zip(dep.iter().zip(lim))
            {
                if d < m {
                    for j in 0..4 {
                        a4[j] += weight * r4[j];
                    }
                }
            }
        });
    Ok(())
}

/// `acc += under * (1 - acc.alpha)`: the accumulated layer over the static one.
pub fn over(acc: &mut [f32], under: &[f32]) -> Result<()> {
    if acc.len() != under.len() || acc.len() % 4 != 0 {
        return Err(Error::shape("under", "must have the shape of acc, (N*4,)"));
    }
    acc.par_chunks_mut(4 * CHUNK)
        .zip(under.par_chunks(4 * CHUNK))
        .for_each(|(a, u)| {
            for (a4, u4) in a.chunks_exact_mut(4).zip(u.chunks_exact(4)) {
                let k = 1.0 - a4[3];
                for j in 0..4 {
                    a4[j] += k * u4[j];
                }
            }
        });
    Ok(())
}

/// Per sample, layer `a` composited with layer `b` by depth, into `b`: the nearer one *over*
/// the farther one (premultiplied), the smaller depth and the nearer one's id. Exact for
/// opaque surfaces and for one transparent surface per layer and sample. `a_*` cover `rect`,
/// `b_*` the whole buffer.
pub fn composite(
    a_rgba: &[f32],
    a_depth: &[f32],
    a_ids: &[i32],
    b_rgba: &mut [f32],
    b_depth: &mut [f32],
    b_ids: &mut [i32],
    rect: Rect,
) -> Result<()> {
    let n = rect.width * rect.height;
    if a_rgba.len() != 4 * n || a_depth.len() != n || a_ids.len() != n {
        return Err(Error::shape(
            "a",
            "rgba (h,w,4), depth and ids (h,w) must cover the rectangle",
        ));
    }
    let stride = rect.stride;
    if stride == 0 || b_depth.len() % stride != 0 {
        return Err(Error::shape("b", "must be (H,W) buffers"));
    }
    let rows = b_depth.len() / stride;
    if b_rgba.len() != 4 * rows * stride || b_ids.len() != rows * stride {
        return Err(Error::shape(
            "b",
            "rgba (H,W,4), depth and ids (H,W) must match",
        ));
    }
    if rect.x0 + rect.width > stride || rect.y0 + rect.height > rows {
        return Err(Error::shape("a", "the rectangle must lie inside b"));
    }
    if n == 0 {
        return Ok(());
    }
    b_rgba
        .par_chunks_mut(4 * stride)
        .zip(b_depth.par_chunks_mut(stride))
        .zip(b_ids.par_chunks_mut(stride))
        .enumerate()
        .skip(rect.y0)
        .take(rect.height)
        .for_each(|(y, ((rgba, depth), ids))| {
            let ry = y - rect.y0;
            for i in 0..rect.width {
                let s = ry * rect.width + i;
                let d = rect.x0 + i;
                let ad = a_depth[s];
                if ad == f32::INFINITY {
                    continue; // nothing in a
                }
                let a4 = [
                    a_rgba[4 * s],
                    a_rgba[4 * s + 1],
                    a_rgba[4 * s + 2],
                    a_rgba[4 * s + 3],
                ];
                let b4 = [
                    rgba[4 * d],
                    rgba[4 * d + 1],
                    rgba[4 * d + 2],
                    rgba[4 * d + 3],
                ];
                let (near, far) = if ad <= depth[d] { (a4, b4) } else { (b4, a4) };
                let k = 1.0 - near[3];
                for j in 0..4 {
                    rgba[4 * d + j] = near[j] + k * far[j];
                }
                if ad <= depth[d] {
                    depth[d] = ad;
                    ids[d] = a_ids[s];
                }
            }
        });
    Ok(())
}

/// A layer written in place: row-major `rgba` (4 per sample, premultiplied), `depth` and `ids`
/// (one per sample), whole buffers.
#[derive(Debug)]
pub struct BuffersMut<'a> {
    /// Premultiplied RGBA, 4 per sample.
    pub rgba: &'a mut [f32],
    /// Depth, `inf` where empty.
    pub depth: &'a mut [f32],
    /// Object ids, -1 where empty.
    pub ids: &'a mut [i32],
}

/// Resolve a supersampled layer into a rectangle of a pixel-size one: `rgba` (4 per sample),
/// `depth` and `ids` are `(rect.height * s) x (rect.width * s)` samples; each pixel of `rect`
/// in `out` (whole buffers, `rect.stride` pixels wide) gets the mean colour of its `s x s`
/// samples and the depth and id of the nearest one (the first in row order on ties).
pub fn resolve(
    rgba: &[f32],
    depth: &[f32],
    ids: &[i32],
    s: usize,
    out: BuffersMut<'_>,
    rect: Rect,
) -> Result<()> {
    let BuffersMut {
        rgba: out_rgba,
        depth: out_depth,
        ids: out_ids,
    } = out;
    let (sw, sh) = (rect.width * s, rect.height * s);
    if s == 0 || rgba.len() != 4 * sw * sh || depth.len() != sw * sh || ids.len() != sw * sh {
        return Err(Error::shape(
            "rgba",
            "rgba (h*s,w*s,4), depth and ids (h*s,w*s) expected",
        ));
    }
    let stride = rect.stride;
    if stride == 0 || out_depth.len() % stride != 0 {
        return Err(Error::shape("out", "must be (H,W) buffers"));
    }
    let rows = out_depth.len() / stride;
    if out_rgba.len() != 4 * rows * stride || out_ids.len() != rows * stride {
        return Err(Error::shape(
            "out",
            "rgba (H,W,4), depth and ids (H,W) must match",
        ));
    }
    if rect.x0 + rect.width > stride || rect.y0 + rect.height > rows {
        return Err(Error::shape("rgba", "the rectangle must lie inside out"));
    }
    let norm = 1.0 / (s * s) as f32;
    out_rgba
        .par_chunks_mut(4 * stride)
        .zip(out_depth.par_chunks_mut(stride))
        .zip(out_ids.par_chunks_mut(stride))
        .enumerate()
        .skip(rect.y0)
        .take(rect.height)
        .for_each(|(y, ((orow, drow), irow))| {
            let ry = y - rect.y0;
            for x in 0..rect.width {
                let mut c = [0.0f32; 4];
                let (mut d, mut id) = (f32::INFINITY, -1);
                let mut first = true;
                for dy in 0..s {
                    let row = (ry * s + dy) * sw + x * s;
                    for dx in 0..s {
                        let k = row + dx;
                        for (ch, v) in c.iter_mut().zip(&rgba[4 * k..4 * k + 4]) {
                            *ch += v;
                        }
                        if first || depth[k] < d {
                            d = depth[k];
                            id = ids[k];
                            first = false;
                        }
                    }
                }
                let o = rect.x0 + x;
                for (dst, v) in orow[4 * o..4 * o + 4].iter_mut().zip(c) {
                    *dst = v * norm;
                }
                drow[o] = d;
                irow[o] = id;
            }
        });
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn out<'a>(rgba: &'a mut [f32], depth: &'a mut [f32], ids: &'a mut [i32]) -> BuffersMut<'a> {
        BuffersMut { rgba, depth, ids }
    }

    #[test]
    fn masked_weighted_sum_then_over() {
        let mut acc = vec![0.0f32; 8];
        let rgba = [1.0, 0.5, 0.25, 1.0, 1.0, 1.0, 1.0, 1.0];
        let depth = [1.0, 3.0];
        let limit = [2.0, 2.0];
        accumulate(&mut acc, &rgba, &depth, Some(&limit), 0.5, Rect::whole(2)).unwrap();
        assert_eq!(acc, vec![0.5, 0.25, 0.125, 0.5, 0.0, 0.0, 0.0, 0.0]);
        over(&mut acc, &[0.0, 0.0, 1.0, 1.0, 0.0, 1.0, 0.0, 1.0]).unwrap();
        assert_eq!(acc, vec![0.5, 0.25, 0.625, 1.0, 0.0, 1.0, 0.0, 1.0]);
    }

    #[test]
    fn no_limit_adds_everywhere_and_shapes_are_checked() {
        let mut acc = vec![1.0f32; 4];
        let one = Rect::whole(1);
        accumulate(&mut acc, &[1.0; 4], &[f32::INFINITY], None, 2.0, one).unwrap();
        assert_eq!(acc, vec![3.0; 4]);
        assert!(accumulate(&mut acc, &[1.0; 8], &[1.0], None, 1.0, one).is_err());
        assert!(accumulate(&mut acc, &[1.0; 4], &[1.0], Some(&[]), 1.0, one).is_err());
        assert!(accumulate(&mut acc, &[1.0; 4], &[1.0], None, f32::NAN, one).is_err());
        let outside = Rect { x0: 1, ..one };
        assert!(accumulate(&mut acc, &[1.0; 4], &[1.0], None, 1.0, outside).is_err());
        assert!(over(&mut acc, &[0.0; 8]).is_err());
    }

    #[test]
    fn a_rectangle_lands_at_its_offset() {
        // buffer 3 wide, 2 high; a 2x1 rectangle at (1, 1)
        let mut acc = vec![0.0f32; 4 * 6];
        let limit = [9.0f32, 9.0, 9.0, 9.0, 0.5, 9.0];
        let rect = Rect {
            x0: 1,
            y0: 1,
            width: 2,
            height: 1,
            stride: 3,
        };
        accumulate(&mut acc, &[1.0; 8], &[1.0, 1.0], Some(&limit), 1.0, rect).unwrap();
        let alpha: Vec<f32> = acc.chunks_exact(4).map(|c| c[3]).collect();
        assert_eq!(alpha, vec![0.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
    }

    #[test]
    fn composite_puts_the_nearer_layer_over() {
        // b: 2 samples, opaque red at depth 2 and empty
        let mut b_rgba = vec![1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0];
        let mut b_depth = vec![2.0, f32::INFINITY];
        let mut b_ids = vec![7, -1];
        // a: half-transparent green in front of the first, and behind nothing on the second
        let a_rgba = [0.0, 0.5, 0.0, 0.5, 0.0, 0.25, 0.0, 0.25];
        let rect = Rect::whole(2);
        composite(
            &a_rgba,
            &[1.0, 5.0],
            &[3, 4],
            &mut b_rgba,
            &mut b_depth,
            &mut b_ids,
            rect,
        )
        .unwrap();
        assert_eq!(b_rgba, vec![0.5, 0.5, 0.0, 1.0, 0.0, 0.25, 0.0, 0.25]);
        assert_eq!(b_depth, vec![1.0, 5.0]);
        assert_eq!(b_ids, vec![3, 4]);
        // a behind an opaque b leaves b
        let mut b2 = vec![1.0, 0.0, 0.0, 1.0];
        let (mut d2, mut i2) = (vec![1.0], vec![7]);
        composite(
            &[0.0, 1.0, 0.0, 1.0],
            &[3.0],
            &[3],
            &mut b2,
            &mut d2,
            &mut i2,
            Rect::whole(1),
        )
        .unwrap();
        assert_eq!((b2, d2, i2), (vec![1.0, 0.0, 0.0, 1.0], vec![1.0], vec![7]));
        assert!(composite(
            &[0.0; 4],
            &[1.0],
            &[0],
            &mut [0.0; 4],
            &mut [1.0],
            &mut [0],
            Rect {
                x0: 1,
                ..Rect::whole(1)
            }
        )
        .is_err());
    }

    #[test]
    fn independent_of_the_thread_count() {
        let n = 3 * CHUNK + 17;
        let rgba: Vec<f32> = (0..4 * n).map(|i| (i % 13) as f32 * 0.1).collect();
        let depth: Vec<f32> = (0..n).map(|i| (i % 7) as f32).collect();
        let limit: Vec<f32> = (0..n).map(|i| (i % 5) as f32).collect();
        let run = |threads| {
            crate::on_threads(threads, || {
                let mut acc = vec![0.0f32; 4 * n];
                accumulate(&mut acc, &rgba, &depth, Some(&limit), 0.3, Rect::whole(n)).unwrap();
                over(&mut acc, &rgba).unwrap();
                acc
            })
        };
        assert_eq!(run(1), run(2));
    }

    #[test]
    fn resolve_means_colour_and_keeps_the_first_nearest_sample() {
        // one 2x2 block -> pixel (1, 0) of a 3x1 buffer; samples 1 and 2 tie at depth 1
        let rgba: Vec<f32> = (0..16).map(|k| k as f32).collect();
        let depth = [2.0, 1.0, 1.0, f32::INFINITY];
        let ids = [7, 8, 9, -1];
        let (mut o, mut d, mut i) = (vec![-1.0f32; 12], vec![-1.0f32; 3], vec![-5i32; 3]);
        let rect = Rect {
            x0: 1,
            y0: 0,
            width: 1,
            height: 1,
            stride: 3,
        };
        resolve(&rgba, &depth, &ids, 2, out(&mut o, &mut d, &mut i), rect).unwrap();
        assert_eq!(&o[4..8], &[6.0, 7.0, 8.0, 9.0]);
        assert_eq!((d[1], i[1]), (1.0, 8));
        assert_eq!((d[0], i[0], d[2], i[2]), (-1.0, -5, -1.0, -5));
        let bad = Rect { x0: 3, ..rect };
        assert!(resolve(&rgba, &depth, &ids, 2, out(&mut o, &mut d, &mut i), bad).is_err());
    }
}
