//! What `opaque_image`'s coverage glow ([`super::coverage_blur`]) cuts its layers from: the
//! sharp frame, a moving object's labels and velocity groups, and one pixel of a group's layer
//! and depth layer (the module docs of `coverage_blur`).
use super::coverage::Window;

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
