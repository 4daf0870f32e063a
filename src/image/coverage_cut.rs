//! What `opaque_image`'s coverage glow ([`super::coverage_blur`]) cuts its layers from: the
//! sharp frame, a moving object's labels and velocity groups, and one pixel of a group's layer
//! and depth layer (the module docs of `coverage_blur`).
use std::mem::MaybeUninit;

use rayon::prelude::*;

use super::coverage::Window;
use super::{pooled, put4};

/// The sharp frame the layers are cut from: its `(h, w, 4)` colour with, optionally, a window
/// of colour `(y1 - y0, x1 - x0, 4)` laid over it (the moving objects drawn over a kept static
/// layer), and its `(h, w)` depth.
#[derive(Clone, Copy, Debug)]
pub struct CoverageSource<'a> {
    /// `(h, w, 4)` premultiplied colour.
    pub rgba: &'a [f32],
    /// A window of colour laid over `rgba`, or none.
    pub pasted: Option<(Window, &'a [f32])>,
    /// `(h, w)` depth.
    pub depth: &'a [f32],
}

/// One velocity group of an object: the window its blurred layer covers (frame pixels), the
/// direction and length of its box blur, and whether it is blurred at all.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoveragePart {
    /// The window its blurred layer covers.
    pub window: Window,
    /// The direction of the box blur (pixels).
    pub direction: [f32; 2],
    /// The length of the box blur (pixels).
    pub length: f32,
    /// Whether the group is blurred (else its layer is composited as it is).
    pub blur: bool,
}

/// A moving object: the window of its pixels, their labels there (`(y1 - y0, x1 - x0)`: the
/// index in `parts` of each pixel's velocity group, `-1` for pixels of other objects) and its
/// velocity groups. Every pixel of a group lies in the group's window.
#[derive(Clone, Copy, Debug)]
pub struct CoverageObject<'a> {
    /// The window of the object's pixels.
    pub window: Window,
    /// Each pixel's group there (`-1`: not the object's).
    pub labels: &'a [i32],
    /// The velocity groups, in the order they are summed.
    pub parts: &'a [CoveragePart],
}

/// One pixel of the layer and of the depth layer `(zw zm, 0, 0, zm)` of group `label` (module
/// docs) at `(y, x)`: `labels` the object's labels on row `y` (if it meets the object, from
/// column `ox0`), `pasted` the pasted colour on row `y` (if it meets the window, from column
/// `px0` to `px1`).
#[inline(always)]
pub(super) fn cut_pixel(
    source: &CoverageSource,
    (labels, ox0): (Option<&[i32]>, usize),
    pasted: Option<(usize, usize, &[f32])>,
    label: i32,
    (y, x, w): (usize, usize, usize),
) -> ([f32; 4], [f32; 4]) {
    let lab = match labels {
        Some(l) if x >= ox0 && x - ox0 < l.len() => l[x - ox0],
        _ => -1,
    };
    let zm = if lab == label { 1.0f32 } else { 0.0 };
    let zw = if lab >= 0 {
        source.depth[y * w + x]
    } else {
        0.0
    };
    let p: &[f32] = match pasted {
        Some((px0, px1, part)) if (px0..px1).contains(&x) => {
            &part[(x - px0) * 4..(x - px0) * 4 + 4]
        }
        _ => &source.rgba[(y * w + x) * 4..(y * w + x) * 4 + 4],
    };
    (
        [p[0] * zm, p[1] * zm, p[2] * zm, p[3] * zm],
        [zw * zm, 0.0, 0.0, zm],
    )
}

/// The object's labels on row `y` (from column `ox0`), if the row meets its window.
pub(super) fn label_row<'a>(object: &CoverageObject<'a>, y: usize) -> (Option<&'a [i32]>, usize) {
    let (oy0, oy1, ox0, ox1) = object.window;
    let ocols = ox1 - ox0;
    let row = (oy0..oy1)
        .contains(&y)
        .then(|| &object.labels[(y - oy0) * ocols..(y - oy0 + 1) * ocols]);
    (row, ox0)
}

/// The pasted colour on row `y` (columns `px0 .. px1`), if the row meets its window.
pub(super) fn pasted_row<'a>(
    source: &CoverageSource<'a>,
    y: usize,
) -> Option<(usize, usize, &'a [f32])> {
    source.pasted.and_then(|((py0, py1, px0, px1), part)| {
        (py0..py1).contains(&y).then(|| {
            let pc = px1 - px0;
            (px0, px1, &part[(y - py0) * pc * 4..(y - py0 + 1) * pc * 4])
        })
    })
}

/// The layer and the depth layer `(zw zm, 0, 0, zm)` of group `label` over `window` (the
/// module docs of `coverage_blur`), each `(y1 - y0, x1 - x0, 4)`, or `(x1 - x0, y1 - y0, 4)`
/// transposed (`transposed`: the window's column `c` is row `c`). With `only` (the group's
/// label), only the group's pixels are cut, over zeros: the same layers up to the sign of a
/// zero where every colour and depth is finite (`coverage_oblique`).
pub(super) fn cut(
    source: &CoverageSource,
    object: &CoverageObject,
    label: i32,
    window: Window,
    w: usize,
    (transposed, only): (bool, Option<i32>),
) -> (Vec<f32>, Vec<f32>) {
    let (y0, y1, x0, x1) = window;
    let (cols, rows) = (x1 - x0, y1 - y0);
    let n = rows * cols * 4;
    let fill = |out: &mut [MaybeUninit<f32>], depth_layer: bool| {
        let pick = |(l, z): ([f32; 4], [f32; 4])| if depth_layer { z } else { l };
        if only.is_some() {
            sparse(out, (source, object, label), window, w, transposed, pick);
        } else if !transposed {
            out.par_chunks_mut(cols * 4).enumerate().for_each(|(r, o)| {
                let y = y0 + r;
                let (labels, pasted) = (label_row(object, y), pasted_row(source, y));
                for c in 0..cols {
                    put4(
                        o,
                        c,
                        pick(cut_pixel(source, labels, pasted, label, (y, x0 + c, w))),
                    );
                }
            });
        } else {
            out.par_chunks_mut(rows * 4).enumerate().for_each(|(c, o)| {
                for r in 0..rows {
                    let y = y0 + r;
                    let (labels, pasted) = (label_row(object, y), pasted_row(source, y));
                    put4(
                        o,
                        r,
                        pick(cut_pixel(source, labels, pasted, label, (y, x0 + c, w))),
                    );
                }
            });
        }
    };
    (pooled(n, |u| fill(u, false)), pooled(n, |u| fill(u, true)))
}

/// `cut`'s rows of the group's pixels only: each row zeros, then the group's pixels of
/// the object's labels along it cut by `cut_pixel` (`pick`: the layer or the depth layer).
fn sparse(
    out: &mut [MaybeUninit<f32>],
    (source, object, label): (&CoverageSource, &CoverageObject, i32),
    (y0, y1, x0, x1): Window,
    w: usize,
    transposed: bool,
    pick: impl Fn(([f32; 4], [f32; 4])) -> [f32; 4] + Sync,
) {
    let (oy0, oy1, ox0, ox1) = object.window;
    let ocols = ox1 - ox0;
    // the window's rows and columns that meet the object's
    let (ra, rb) = (oy0.max(y0), oy1.min(y1));
    let (ca, cb) = (ox0.max(x0), ox1.min(x1));
    let len = if transposed { y1 - y0 } else { x1 - x0 };
    out.par_chunks_mut(len * 4).enumerate().for_each(|(k, o)| {
        o.fill(MaybeUninit::new(0.0));
        // (frame pixels (y, x) along oriented row k, and their place in it)
        let mut put = |y: usize, x: usize, at: usize| {
            if object.labels[(y - oy0) * ocols + x - ox0] == label {
                let (labels, pasted) = (label_row(object, y), pasted_row(source, y));
                put4(
                    o,
                    at,
                    pick(cut_pixel(source, labels, pasted, label, (y, x, w))),
                );
            }
        };
        if transposed {
            let x = x0 + k;
            if (ca..cb).contains(&x) {
                (ra..rb).for_each(|y| put(y, x, y - y0));
            }
        } else {
            let y = y0 + k;
            if (ra..rb).contains(&y) {
                (ca..cb).for_each(|x| put(y, x, x - x0));
            }
        }
    });
}
