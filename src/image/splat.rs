//! Splatting along image paths: the time average of points that move across the image, the
//! scatter form of motion blur. Each source (a pixel of a sharp render, say) carries a
//! premultiplied colour and the polyline its image follows during the shutter; the output holds,
//! per pixel, the sum over sources of colour times the fraction of the shutter the source spends
//! there. Unlike a gather blur along one direction, every source keeps its own path, so points at
//! different depths (which move at different image speeds under perspective) and points of
//! different objects each blur by their own motion. The motion volume's per-pixel colours use it
//! (`motionblur.methods.motion_volume`).
use rayon::prelude::*;

use crate::error::{Error, Result};

/// Most polyline points per source.
pub const MAX_PATH_POINTS: usize = 256;

/// Largest output accepted (pixels), as for the rasterizer.
const MAX_PIXELS: usize = 1 << 25;

/// Sources are split into this many fixed runs, each splatted into its own buffer, and the
/// buffers are summed in run order: the same sums for any thread count.
const RUNS: usize = 8;

/// The parameter interval `[u0, u1]` of `a + u (b - a)`, `u` in [0, 1], inside the rectangle
/// `[lo, hi]` on both axes (Liang-Barsky), or `None`.
fn clip(a: [f32; 2], b: [f32; 2], lo: [f32; 2], hi: [f32; 2]) -> Option<(f32, f32)> {
    let (mut u0, mut u1) = (0.0f32, 1.0f32);
    for k in 0..2 {
        let d = b[k] - a[k];
        if d == 0.0 {
            if a[k] < lo[k] || a[k] > hi[k] {
                return None;
            }
            continue;
        }
        let (mut s, mut t) = ((lo[k] - a[k]) / d, (hi[k] - a[k]) / d);
        if s > t {
            std::mem::swap(&mut s, &mut t);
        }
        u0 = u0.max(s);
        u1 = u1.min(t);
        if u0 > u1 {
            return None;
        }
    }
    Some((u0, u1))
}

/// Adds `c * wgt` at image position `(x, y)` (pixel centres at +0.5), bilinearly.
#[inline]
pub(super) fn splat(
    out: &mut [[f32; 4]],
    w: usize,
    h: usize,
    x: f32,
    y: f32,
    c: [f32; 4],
    wgt: f32,
) {
    let (px, py) = (x - 0.5, y - 0.5);
    let (fx, fy) = (px.floor(), py.floor());
    let (ax, ay) = (px - fx, py - fy);
    let (i0, j0) = (fx as i64, fy as i64);
    for (dj, wy) in [(0i64, 1.0 - ay), (1, ay)] {
        let j = j0 + dj;
        if j < 0 || j >= h as i64 || wy == 0.0 {
            continue;
        }
        for (di, wx) in [(0i64, 1.0 - ax), (1, ax)] {
            let i = i0 + di;
            if i < 0 || i >= w as i64 || wx == 0.0 {
                continue;
            }
            add(out, j as usize * w + i as usize, c, wgt * wx * wy);
        }
    }
}

/// Adds `c * wgt` to pixel `o` (an index into the `(h, w)` pixels of `out`).
#[inline(always)]
fn add(out: &mut [[f32; 4]], o: usize, c: [f32; 4], wgt: f32) {
    // one 4-wide load and store per pixel (split stores would stall the next 4-wide load of a
    // pixel the neighbouring sources just wrote)
    let p = &mut out[o];
    *p = [
        p[0] + c[0] * wgt,
        p[1] + c[1] * wgt,
        p[2] + c[2] * wgt,
        p[3] + c[3] * wgt,
    ];
}

/// Adds `c * time` spread along the segment `a -> b` at uniform speed: per pixel column (rows
/// for a mostly vertical segment) the share of the segment's extent inside it, at the segment's
/// height at the column's centre, split between the two nearest rows (a line drawn with
/// Xiaolin Wu's weights, the time in each column exact).
///
/// `breaks`: points on the segment (in order from `a` to `b`) where it is cut into parts, each column evaluated per part as if the parts were separate segments (a
/// uniform straight polyline drawn as one segment, with its joins' columns split as its own
/// segments would split them).
///
/// The columns a part crosses completely (weight `per`, height at `i + 0.5`) run in a tight
/// loop; the partial columns at its ends take the general form. Both give the same floats as
/// evaluating the general form everywhere.
///
/// The segment `[a, b]` is clipped to the image grown by one pixel on every side.
fn segment(
    out: &mut [[f32; 4]],
    w: usize,
    h: usize,
    [a, b]: [[f32; 2]; 2],
    c: [f32; 4],
    time: f32,
    breaks: &[[f32; 2]],
) {
    let (lo, hi) = ([-1.0f32, -1.0], [w as f32 + 1.0, h as f32 + 1.0]);
    let d = [b[0] - a[0], b[1] - a[1]];
    // major axis k, minor axis 1 - k
    let k = usize::from(d[1].abs() > d[0].abs());
    let m = 1 - k;
    if d[k].abs() < 1e-6 {
        splat(out, w, h, 0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), c, time);
        return;
    }
    let Some((u0, u1)) = clip(a, b, lo, hi) else {
        return;
    };
    let (s0, s1) = (a[k] + u0 * d[k], a[k] + u1 * d[k]);
    let (s0, s1) = (s0.min(s1), s0.max(s1));
    let (size_k, size_m) = if k == 0 { (w, h) } else { (h, w) };
    let slope = d[m] / d[k];
    let line = Line {
        per: time / d[k].abs(), // time per unit of the major axis
        slope,
        // y >= -1.5 after clipping: the truncation of y + 2 is floor(y) + 2 (no libm floor call)
        base: a[m] - slope * a[k] - 0.5 + 2.0,
        size_k: size_k as i64,
        rows: size_m as i64,
        // offsets of one step along the major and the minor axis (pixels)
        sk: if k == 0 { 1 } else { w },
        sm: if k == 0 { w } else { 1 },
        c,
    };
    if breaks.is_empty() {
        line.run(out, s0, s1);
        return;
    }
    // the parts in increasing major coordinate, cut to [s0, s1]
    let mut from = s0;
    let mut cut = |out: &mut [[f32; 4]], x: f32| {
        let x = x.min(s1);
        if x > from {
            line.run(out, from, x);
            from = x;
        }
    };
    if d[k] > 0.0 {
        breaks.iter().for_each(|x| cut(out, x[k]));
    } else {
        breaks.iter().rev().for_each(|x| cut(out, x[k]));
    }
    cut(out, s1);
}

/// The straight line of [`segment`] in its major axis frame.
struct Line {
    per: f32,
    slope: f32,
    base: f32,
    size_k: i64,
    rows: i64,
    sk: usize,
    sm: usize,
    c: [f32; 4],
}

impl Line {
    /// The columns of the major range `[s0, s1]`.
    #[inline(always)]
    fn run(&self, out: &mut [[f32; 4]], s0: f32, s1: f32) {
        let &Line {
            per,
            slope,
            base,
            size_k,
            rows,
            sk,
            sm,
            c,
        } = self;
        // a column crossed in part: its weight and its height at the part's middle
        let part = |i: i64| {
            let (x0, x1) = ((i as f32).max(s0), (i as f32 + 1.0).min(s1));
            (x1 > x0).then_some((per * (x1 - x0), base + slope * (0.5 * (x0 + x1))))
        };
        let first = floor(s0).max(0);
        let last = ceil(s1).min(size_k);
        // the columns inside [s0, s1] completely: [ceil(s0), floor(s1))
        let (full0, full1) = (ceil(s0).max(first), floor(s1).min(last));
        if full0 >= full1 {
            for i in first..last {
                if let Some((wgt, y)) = part(i) {
                    column(out, i as usize * sk, sm, rows, c, wgt, y);
                }
            }
            return;
        }
        // at most one partial column at each end
        if first < full0 {
            if let Some((wgt, y)) = part(first) {
                column(out, first as usize * sk, sm, rows, c, wgt, y);
            }
        }
        let mut o = full0 as usize * sk;
        for i in full0..full1 {
            let y = base + slope * (i as f32 + 0.5);
            column(out, o, sm, rows, c, per, y);
            o += sk;
        }
        if full1 < last {
            if let Some((wgt, y)) = part(full1) {
                column(out, full1 as usize * sk, sm, rows, c, wgt, y);
            }
        }
    }
}

/// `v.floor()` as an integer for finite `v` of moderate size (no libm call).
#[inline(always)]
fn floor(v: f32) -> i64 {
    let t = v as i64;
    if (t as f32) > v {
        t - 1
    } else {
        t
    }
}

/// `v.ceil()` as an integer for finite `v` of moderate size (no libm call).
#[inline(always)]
fn ceil(v: f32) -> i64 {
    let t = v as i64;
    if (t as f32) < v {
        t + 1
    } else {
        t
    }
}

/// One column of [`segment`] starting at pixel `o` (rows `sm` pixels apart, `rows` of them):
/// `c * wgt` at minor coordinate `y` (+ 2), split between the two nearest rows.
#[inline(always)]
fn column(out: &mut [[f32; 4]], o: usize, sm: usize, rows: i64, c: [f32; 4], wgt: f32, y: f32) {
    // y is finite and within a few pixels of the image after clipping: i32 holds it
    let jt = y as i32;
    let t = y - jt as f32;
    let j0 = jt as i64 - 2;
    if (j0 as u64) < (rows - 1) as u64 {
        let o0 = o + j0 as usize * sm;
        add(out, o0, c, wgt * (1.0 - t));
        add(out, o0 + sm, c, wgt * t);
    } else {
        for (j, wy) in [(j0, 1.0 - t), (j0 + 1, t)] {
            if (0..rows).contains(&j) {
                add(out, o + j as usize * sm, c, wgt * wy);
            }
        }
    }
}

/// Splats `colors[i]` (premultiplied RGBA) along the polyline `paths[i * p .. (i + 1) * p]`
/// (pixel coordinates of a `w` x `h` image, centres at +0.5): the shutter is split equally among
/// the `p - 1` segments (one point: the source stands still), each crossed at uniform speed
/// (`segment`). Returns the `(h, w, 4)` time-averaged image, row-major.
/// A segment with a non-finite end contributes nothing (a point behind the camera), as do the
/// parts of paths outside the image.
pub fn splat_paths(
    w: usize,
    h: usize,
    colors: &[[f32; 4]],
    paths: &[[f32; 2]],
    p: usize,
) -> Result<Vec<f32>> {
    if w == 0 || h == 0 || w.saturating_mul(h) > MAX_PIXELS {
        return Err(Error::value(
            "size",
            format!("expected 1..={MAX_PIXELS} pixels, got {w}x{h}"),
        ));
    }
    if p == 0 || p > MAX_PATH_POINTS {
        return Err(Error::shape(
            "paths",
            format!("expected 1..={MAX_PATH_POINTS} points per path, got {p}"),
        ));
    }
    if paths.len() != colors.len() * p {
        return Err(Error::shape(
            "paths",
            format!(
                "expected {} points ({} sources x {p}), got {}",
                colors.len() * p,
                colors.len(),
                paths.len()
            ),
        ));
    }
    if colors.iter().flatten().any(|v| !v.is_finite()) {
        return Err(Error::value("colors", "contains NaN or inf"));
    }
    let n = colors.len();
    let run = n.div_ceil(RUNS).max(1);
    super::check_splat_buffers("splat_paths", w, h, n.div_ceil(run))?;
    let buffers: Vec<Vec<[f32; 4]>> = (0..n.div_ceil(run))
        .into_par_iter()
        .map(|r| {
            let mut out = vec![[0.0f32; 4]; w * h];
            for i in r * run..((r + 1) * run).min(n) {
                trace(&mut out, w, h, colors[i], &paths[i * p..(i + 1) * p]);
            }
            out
        })
        .collect();
    Ok(sum_buffers(buffers, w * h))
}

/// Splats `c` along the polyline `path` into `out` (`w` x `h` pixels), the shutter split
/// equally among its segments; see [`splat_paths`].
pub(super) fn trace(out: &mut [[f32; 4]], w: usize, h: usize, c: [f32; 4], path: &[[f32; 2]]) {
    if c == [0.0; 4] {
        return;
    }
    if path.len() == 1 {
        if path[0].iter().all(|v| v.is_finite()) {
            splat(out, w, h, path[0][0], path[0][1], c, 1.0);
        }
        return;
    }
    let seg_time = 1.0 / (path.len() - 1) as f32;
    for s in path.windows(2) {
        let (a, b) = (s[0], s[1]);
        if a.iter().chain(&b).all(|v| v.is_finite()) {
            segment(out, w, h, [a, b], c, seg_time, &[]);
        }
    }
}

/// [`trace`] of a path of 3 points or more, all finite, whose points lie (near enough) on the
/// uniform straight motion from its first to its last and whose segments share their major
/// axis and are no point splats: drawn as one segment cut at the path's inner points, the same
/// sums as `trace` up to rounding without a segment's set-up per path point.
pub(super) fn trace_straight(
    out: &mut [[f32; 4]],
    w: usize,
    h: usize,
    c: [f32; 4],
    path: &[[f32; 2]],
) {
    if c == [0.0; 4] {
        return;
    }
    let n = path.len();
    segment(out, w, h, [path[0], path[n - 1]], c, 1.0, &path[1..n - 1]);
}

/// The per-run buffers (each `n` pixels) summed in run order (the same sums for any thread
/// count), flattened to `(n, 4)` floats.
pub(super) fn sum_buffers(buffers: Vec<Vec<[f32; 4]>>, n: usize) -> Vec<f32> {
    let mut it = buffers.into_iter();
    let mut sum = it.next().unwrap_or_else(|| vec![[0.0f32; 4]; n]);
    for b in it {
        sum.par_iter_mut().zip(b).for_each(|(s, v)| {
            for ch in 0..4 {
                s[ch] += v[ch];
            }
        });
    }
    sum.into_flattened()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_still_point_and_a_horizontal_path_keep_their_colour_total() {
        let c = [0.5, 0.25, 0.125, 1.0];
        // still, on a pixel centre: all of it in that pixel
        let out = splat_paths(8, 4, &[c], &[[2.5, 1.5]], 1).unwrap();
        assert_eq!(&out[4 * (8 + 2)..4 * (8 + 3)], &c);
        // 4 pixels along row 1, from centre to centre: a quarter of the time each of pixels
        // 2..=5 (half pixels at the ends)
        let out = splat_paths(8, 4, &[c], &[[2.5, 1.5], [6.5, 1.5]], 2).unwrap();
        let alpha: Vec<f32> = (0..8).map(|x| out[4 * (8 + x) + 3]).collect();
        let total: f32 = alpha.iter().sum();
        assert!((total - 1.0).abs() < 1e-5, "{alpha:?}");
        for x in 3..=5 {
            assert!((alpha[x] - 0.25).abs() < 1e-5, "{alpha:?}");
        }
        assert!((alpha[2] - 0.125).abs() < 1e-5 && (alpha[6] - 0.125).abs() < 1e-5);
    }

    #[test]
    fn paths_leaving_the_image_lose_only_their_outside_part() {
        let c = [1.0; 4];
        // half the path is left of the image
        let out = splat_paths(10, 3, &[c], &[[-9.5, 1.5], [10.5, 1.5]], 2).unwrap();
        let total: f32 = out.iter().skip(3).step_by(4).sum();
        assert!((total - 0.5).abs() < 0.03, "{total}");
        // a non-finite end drops its segment only
        let out = splat_paths(10, 3, &[c], &[[1.5, 1.5], [f32::NAN, 1.5], [5.5, 1.5]], 3).unwrap();
        assert!(out.iter().all(|v| v.is_finite()));
        assert_eq!(
            out.iter().skip(3).step_by(4).filter(|v| **v > 0.0).count(),
            0
        );
    }

    #[test]
    fn a_straight_path_drawn_whole_is_its_segments_drawn_apart() {
        // uniform straight paths (shallow, steep, leaving the image, slower than a pixel per
        // segment) give the segment-by-segment sums up to rounding
        for (a, d) in [
            ([2.3f32, 3.1f32], [3.7f32, 1.3f32]),
            ([20.2, 1.4], [-1.1, 2.9]),
            ([-3.0, 5.5], [4.9, -0.2]),
            ([5.5, 5.2], [0.31, 0.07]),
        ] {
            let path: Vec<[f32; 2]> = (0..9)
                .map(|s| [a[0] + s as f32 * d[0], a[1] + s as f32 * d[1]])
                .collect();
            let c = [0.3, 0.6, 0.9, 1.0];
            let mut apart = vec![[0.0f32; 4]; 24 * 20];
            let mut whole = apart.clone();
            trace(&mut apart, 24, 20, c, &path);
            trace_straight(&mut whole, 24, 20, c, &path);
            for (p, q) in apart.iter().flatten().zip(whole.iter().flatten()) {
                assert!((p - q).abs() < 2e-6, "{a:?} {d:?}: {p} {q}");
            }
            assert!(apart.iter().map(|p| p[3]).sum::<f32>() > 0.2);
        }
    }

    #[test]
    fn bad_input_is_an_error_and_threads_do_not_change_the_sums() {
        let c = [[1.0f32; 4]];
        assert!(splat_paths(0, 3, &c, &[[0.0, 0.0]], 1).is_err());
        assert!(splat_paths(3, 3, &c, &[[0.0, 0.0]], 2).is_err());
        assert!(splat_paths(3, 3, &[[f32::NAN; 4]], &[[0.0, 0.0]], 1).is_err());
        let n = 1000;
        let colors: Vec<[f32; 4]> = (0..n)
            .map(|i| [i as f32 / n as f32, 0.5, 0.25, 1.0])
            .collect();
        let paths: Vec<[f32; 2]> = (0..n)
            .flat_map(|i| {
                let x = (i * 37 % 61) as f32 * 0.7;
                let y = (i * 11 % 43) as f32 * 0.9;
                [[x, y], [x + 13.3, y + 4.1], [x + 20.0, y - 3.0]]
            })
            .collect();
        let one = crate::on_threads(1, || splat_paths(48, 40, &colors, &paths, 3).unwrap());
        let two = crate::on_threads(2, || splat_paths(48, 40, &colors, &paths, 3).unwrap());
        assert_eq!(one, two);
    }
}
