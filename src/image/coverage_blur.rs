//! The `opaque_image` method's coverage glow of one moving object in one call, in place on the
//! output frame: each velocity group's layer cut from the sharp frame, box-blurred along the
//! group's velocity with its depth-times-mask, the groups summed and composited over the
//! static pixels ([`super::coverage`]'s composite).
//!
//! Per velocity group `i` (in order) over its window, with `lab` the object's label of a pixel
//! (`-1` outside the object, its group index inside), `c` the sharp frame's colour and `d` its
//! depth:
//!
//! ```text
//! zm    = 1 if lab == i else 0
//! zw    = d if lab >= 0 else 0
//! layer = c * zm,  zl = (zw * zm, 0, 0, zm)
//! layer, zl = box_blur(layer), box_blur(zl)      (when the group is blurred)
//! acc  += layer,  acc_z += zl                    (on the union of the groups' windows, from 0)
//! ```
//!
//! then the composite of `acc` and `acc_z` over the union window of the output, which holds
//! the static colour (and, after the first object, the objects composited before). In float32,
//! in that order: the bits of the same steps written with numpy arrays (the method's former
//! Python path, kept as the oracle of tests/methods/test_image_space_fast_paths.py). Rows run
//! in parallel, each written from inputs only, so the result does not depend on the thread
//! count.
use rayon::prelude::*;

use super::coverage::{composite_pixel, Window};
use super::coverage_cut::{
    cut, cut_pixel, label_row, pasted_row, CoverageObject, CoveragePart, CoverageSource,
};
use super::coverage_oblique::{add_oblique, finite};
use super::lines::plan;
use super::{box_blur, check_direction, pool};
use crate::error::{Error, Result};

fn check_window(name: &'static str, (y0, y1, x0, x1): Window, w: usize, h: usize) -> Result<()> {
    if !(y0 < y1 && y1 <= h && x0 < x1 && x1 <= w) {
        return Err(Error::value(
            name,
            format!("({y0}, {y1}, {x0}, {x1}) is not a non-empty window of {w}x{h} pixels"),
        ));
    }
    Ok(())
}

fn check_len(name: &'static str, a: &[f32], n: usize, shape: String) -> Result<()> {
    if a.len() != n {
        return Err(Error::shape(name, format!("expected {shape} values")));
    }
    Ok(())
}

/// The union of the parts' windows.
fn union(parts: &[CoveragePart]) -> Window {
    parts.iter().map(|p| p.window).fold(
        (usize::MAX, 0, usize::MAX, 0),
        |(a0, a1, b0, b1), (y0, y1, x0, x1)| (a0.min(y0), a1.max(y1), b0.min(x0), b1.max(x1)),
    )
}

/// The object's coverage glow (module docs) composited in place over `out` (`(h, w, 4)`, the
/// colour so far; `back_depth` `(h, w)` the static depth). Returns the number of pixels kept
/// in front (0 without `layers`).
pub fn coverage_blur(
    (out, back): (&mut [f32], Option<&[f32]>),
    back_depth: &[f32],
    (w, h): (usize, usize),
    source: &CoverageSource,
    object: &CoverageObject,
    layers: bool,
) -> Result<u64> {
    check_len("out", out, w * h * 4, format!("({h},{w},4)"))?;
    if let Some(b) = back {
        check_len("back", b, w * h * 4, format!("({h},{w},4)"))?;
    }
    check_len("back_depth", back_depth, w * h, format!("({h},{w})"))?;
    check_len("rgba", source.rgba, w * h * 4, format!("({h},{w},4)"))?;
    check_len("depth", source.depth, w * h, format!("({h},{w})"))?;
    if let Some((win @ (y0, y1, x0, x1), part)) = source.pasted {
        check_window("pasted", win, w, h)?;
        let n = (y1 - y0) * (x1 - x0);
        check_len(
            "pasted",
            part,
            n * 4,
            format!("({},{},4)", y1 - y0, x1 - x0),
        )?;
    }
    let (oy0, oy1, ox0, ox1) = object.window;
    check_window("window", object.window, w, h)?;
    if object.labels.len() != (oy1 - oy0) * (ox1 - ox0) {
        return Err(Error::shape(
            "labels",
            format!("expected ({},{}) values", oy1 - oy0, ox1 - ox0),
        ));
    }
    if object.parts.is_empty() {
        return Err(Error::value(
            "parts",
            "expected at least one velocity group",
        ));
    }
    for p in object.parts {
        check_window("parts", p.window, w, h)?;
    }
    if let [part] = object.parts {
        // One group blurred along a row (or not blurred): cut, blur and composite row by row,
        // with no window-sized image in between
        if let Some(radius) = along_rows(part)? {
            return rows((out, back), back_depth, w, source, object, radius, layers);
        }
    }
    let uw @ (uy0, uy1, ux0, ux1) = union(object.parts);
    let (un, ucols) = ((uy1 - uy0) * (ux1 - ux0), ux1 - ux0);
    // the sums from zero (0 + v: the bits of numpy's `+=` into zeros, -0 included)
    let zeros = || -> Vec<f32> {
        let mut v = pool::try_take(un * 4).unwrap_or_default();
        v.resize(un * 4, 0.0);
        v.par_chunks_mut(1 << 14).for_each(|c| c.fill(0.0));
        v
    };
    let (mut acc, mut acc_z) = (zeros(), zeros());
    let mut all_finite = None;
    for (i, part) in object.parts.iter().enumerate() {
        if let Some(radius) = along_rows(part)? {
            add_rows((&mut acc, &mut acc_z), uw, source, object, i, radius, w)?;
            continue;
        }
        let oblique = plan(part.direction, part.length * 0.5).filter(|p| p.slope != 0.0);
        if let Some(p) = oblique.filter(|_| part.blur) {
            // (once an object: the first oblique group's check serves the rest)
            let finite = *all_finite.get_or_insert_with(|| finite(source, uw, w));
            let sums = (&mut acc[..], &mut acc_z[..]);
            let group = (source, object, i as i32);
            add_oblique(sums, uw, group, part.window, &p, w, finite)?;
            continue;
        }
        let (mut layer, mut zl) = cut(source, object, i as i32, part.window, w, (false, None));
        if part.blur {
            let (py0, py1, px0, px1) = part.window;
            let (pw, ph) = (px1 - px0, py1 - py0);
            let b = box_blur(&layer, pw, ph, part.direction, part.length)?;
            pool::give(std::mem::replace(&mut layer, b));
            let b = box_blur(&zl, pw, ph, part.direction, part.length)?;
            pool::give(std::mem::replace(&mut zl, b));
        }
        add_window(&mut acc, uw, &layer, part.window);
        add_window(&mut acc_z, uw, &zl, part.window);
        pool::give(layer);
        pool::give(zl);
    }
    let front = over_rows(
        (out, back),
        w,
        uw,
        || (),
        |_, y, row, back_row| {
            let r = y - uy0;
            let mut front = 0u64;
            for c in 0..ucols {
                let i = (r * ucols + c) * 4;
                let x = ux0 + c;
                let b: [f32; 4] = acc[i..i + 4].try_into().expect("four channels");
                let s = back_row.unwrap_or(row)[c * 4..c * 4 + 4]
                    .try_into()
                    .expect("four");
                let z = layers.then(|| (acc_z[i], acc_z[i + 3], back_depth[y * w + x]));
                let (o, near) = composite_pixel(b, s, z);
                front += near as u64;
                row[c * 4..c * 4 + 4].copy_from_slice(&o);
            }
            front
        },
        |a, b| a + b,
    );
    pool::give(acc);
    pool::give(acc_z);
    Ok(front)
}

/// `f(scratch, y, out row's columns x0 .. x1, back row's columns x0 .. x1)` on every row `y`
/// of `window` in parallel, the results combined by `add`. With `back` (the colour so far:
/// `out` then holds nothing yet), every pixel of `out` outside the window is copied from it
/// and `f` reads the colour so far from the back row; without, from `out`'s own row.
fn over_rows<S, T: Default + Send>(
    (out, back): (&mut [f32], Option<&[f32]>),
    w: usize,
    (y0, y1, x0, x1): Window,
    init: impl Fn() -> S + Sync + Send,
    f: impl Fn(&mut S, usize, &mut [f32], Option<&[f32]>) -> T + Sync + Send,
    add: impl Fn(T, T) -> T + Sync + Send,
) -> T {
    out.par_chunks_mut(w * 4)
        .enumerate()
        .skip(if back.is_some() { 0 } else { y0 })
        .take(if back.is_some() { usize::MAX } else { y1 - y0 })
        .map_init(init, |s, (y, row)| {
            let inside = (y0..y1).contains(&y);
            match back {
                Some(b) => {
                    let b = &b[y * w * 4..(y + 1) * w * 4];
                    if !inside {
                        row.copy_from_slice(b);
                        return T::default();
                    }
                    row[..x0 * 4].copy_from_slice(&b[..x0 * 4]);
                    row[x1 * 4..].copy_from_slice(&b[x1 * 4..]);
                    f(s, y, &mut row[x0 * 4..x1 * 4], Some(&b[x0 * 4..x1 * 4]))
                }
                None => f(s, y, &mut row[x0 * 4..x1 * 4], None),
            }
        })
        .reduce(T::default, add)
}

/// `coverage_blur` of one group blurred along rows with `radius` taps each side (`None`: not
/// blurred), row by row: each row of the group's window cut, box-filtered as `box_blur`'s rows
/// are, summed from zero and composited in place. Fails as `box_blur` does when a blurred
/// layer holds NaN or infinity (after compositing).
fn rows(
    (out, back): (&mut [f32], Option<&[f32]>),
    back_depth: &[f32],
    w: usize,
    source: &CoverageSource,
    object: &CoverageObject,
    radius: Option<usize>,
    layers: bool,
) -> Result<u64> {
    let part = &object.parts[0];
    let (_, _, x0, x1) = part.window;
    let (front, infinite) = over_rows(
        (out, back),
        w,
        part.window,
        || vec![0.0f32; (x1 - x0) * 6],
        |cut, y, row, back_row| {
            let zb = &back_depth[y * w + x0..y * w + x1];
            let mut front = 0u64;
            let finite = blur_row(cut, (source, object, 0), (y, x0, w), radius, |c, v| {
                // (the sum from zero: 0 + v, the bits of numpy's `+=` into zeros)
                let v = v.map(|v| v + 0.0);
                let s = back_row.unwrap_or(row)[c * 4..c * 4 + 4]
                    .try_into()
                    .expect("four");
                let z = layers.then(|| (v[4], v[5], zb[c]));
                let (o, near) = composite_pixel([v[0], v[1], v[2], v[3]], s, z);
                front += near as u64;
                row[c * 4..c * 4 + 4].copy_from_slice(&o);
            });
            (front, !finite && part.blur)
        },
        |a, b| (a.0 + b.0, a.1 || b.1),
    );
    if infinite {
        return Err(Error::value("rgba", "contains NaN or inf"));
    }
    Ok(front)
}

/// `Some(radius)` when `part` is filtered along rows as `box_blur` filters it (its plan's
/// direction is along x: taps `radius` pixels each side), or not at all (`Some(None)`: not
/// blurred, or a box of one tap); `None` for a sheared or transposed blur. Fails as `box_blur`
/// does on a bad direction or length.
fn along_rows(part: &CoveragePart) -> Result<Option<Option<usize>>> {
    if !part.blur {
        return Ok(Some(None));
    }
    check_direction(part.direction, part.length, "length")?;
    Ok(match plan(part.direction, part.length * 0.5) {
        None => Some(None),
        Some(p) if !p.transpose && p.slope == 0.0 => Some(Some(p.radius)),
        Some(_) => None,
    })
}

/// Row `y` of group `label`'s blurred layer over its window's columns `x0 ..` (`cut.len() / 6`
/// of them): the layer and the depth layer's two live channels cut into `cut` (six values a
/// pixel), then `emit(column, six values)` for each column, filtered with `radius` taps each
/// side as `box_blur`'s rows are (`box_row_each`'s running sums: f64, the same order), or as
/// cut (`None`). Returns whether every cut value is finite.
fn blur_row(
    cut: &mut [f32],
    (source, object, label): (&CoverageSource, &CoverageObject, i32),
    (y, x0, w): (usize, usize, usize),
    radius: Option<usize>,
    mut emit: impl FnMut(usize, [f32; 6]),
) -> bool {
    let cols = cut.len() / 6;
    let (labels, pasted) = (label_row(object, y), pasted_row(source, y));
    let mut finite = true;
    for (c, v) in cut.chunks_exact_mut(6).enumerate() {
        let (l, z) = cut_pixel(source, labels, pasted, label, (y, x0 + c, w));
        v.copy_from_slice(&[l[0], l[1], l[2], l[3], z[0], z[3]]);
        finite &= v.iter().all(|v| v.is_finite());
    }
    let Some(r) = radius else {
        for c in 0..cols {
            emit(c, cut[c * 6..c * 6 + 6].try_into().expect("six"));
        }
        return finite;
    };
    let inv = 1.0 / (2 * r + 1) as f64;
    let px = |i: usize| -> [f64; 6] {
        let p = &cut[i * 6..i * 6 + 6];
        std::array::from_fn(|k| p[k] as f64)
    };
    let mut s = [0.0f64; 6];
    for i in 0..=r.min(cols - 1) {
        let p = px(i);
        for k in 0..6 {
            s[k] += p[k];
        }
    }
    for c in 0..cols {
        emit(c, s.map(|v| (v * inv) as f32));
        if c + r + 1 < cols {
            let p = px(c + r + 1);
            for k in 0..6 {
                s[k] += p[k];
            }
        }
        if c >= r {
            let p = px(c - r);
            for k in 0..6 {
                s[k] -= p[k];
            }
        }
    }
    finite
}

/// Group `label`'s blurred layer and depth layer (`blur_row`, row by row) added into `acc`
/// and `acc_z` (`(y1 - y0, x1 - x0, 4)` over window `aw`; of the depth layer only channels 0
/// and 3, the others being zero and never read). Fails as `box_blur` does when the blurred
/// layer holds NaN or infinity.
fn add_rows(
    (acc, acc_z): (&mut [f32], &mut [f32]),
    aw: Window,
    source: &CoverageSource,
    object: &CoverageObject,
    label: usize,
    radius: Option<usize>,
    w: usize,
) -> Result<()> {
    let part = &object.parts[label];
    let (py0, py1, px0, px1) = part.window;
    let acols = aw.3 - aw.2;
    let infinite = acc
        .par_chunks_mut(acols * 4)
        .zip(acc_z.par_chunks_mut(acols * 4))
        .enumerate()
        .skip(py0 - aw.0)
        .take(py1 - py0)
        .map_init(
            || vec![0.0f32; (px1 - px0) * 6],
            |cut, (r, (a, az))| {
                let (a, az) = (&mut a[(px0 - aw.2) * 4..], &mut az[(px0 - aw.2) * 4..]);
                let lab = label as i32;
                let finite = blur_row(
                    cut,
                    (source, object, lab),
                    (aw.0 + r, px0, w),
                    radius,
                    |c, v| {
                        for k in 0..4 {
                            a[c * 4 + k] += v[k];
                        }
                        az[c * 4] += v[4];
                        az[c * 4 + 3] += v[5];
                    },
                );
                !finite && part.blur
            },
        )
        .reduce(|| false, |a, b| a || b);
    if infinite {
        return Err(Error::value("rgba", "contains NaN or inf"));
    }
    Ok(())
}

/// `acc` (the `(y1 - y0, x1 - x0, 4)` image over window `aw`) += `part` over window `pw`
/// (inside `aw`).
fn add_window(acc: &mut [f32], aw: Window, part: &[f32], pw: Window) {
    let acols = aw.3 - aw.2;
    let (py0, py1, px0, px1) = pw;
    let pcols = px1 - px0;
    acc.par_chunks_mut(acols * 4)
        .enumerate()
        .skip(py0 - aw.0)
        .take(py1 - py0)
        .for_each(|(r, row)| {
            let src = &part[(r + aw.0 - py0) * pcols * 4..][..pcols * 4];
            let dst = &mut row[(px0 - aw.2) * 4..(px1 - aw.2) * 4];
            for (d, s) in dst.iter_mut().zip(src) {
                *d += s;
            }
        });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The module docs step by step, serial, on whole images: the oracle.
    fn serial(
        out: &[f32],
        back_depth: &[f32],
        (w, _h): (usize, usize),
        source: &CoverageSource,
        object: &CoverageObject,
        layers: bool,
    ) -> (Vec<f32>, u64) {
        let (oy0, oy1, ox0, ox1) = object.window;
        let label = |y: usize, x: usize| -> i32 {
            if (oy0..oy1).contains(&y) && (ox0..ox1).contains(&x) {
                object.labels[(y - oy0) * (ox1 - ox0) + x - ox0]
            } else {
                -1
            }
        };
        let colour = |y: usize, x: usize| -> [f32; 4] {
            if let Some(((py0, py1, px0, px1), part)) = source.pasted {
                if (py0..py1).contains(&y) && (px0..px1).contains(&x) {
                    let j = ((y - py0) * (px1 - px0) + x - px0) * 4;
                    return part[j..j + 4].try_into().unwrap();
                }
            }
            source.rgba[(y * w + x) * 4..(y * w + x) * 4 + 4]
                .try_into()
                .unwrap()
        };
        let (uy0, uy1, ux0, ux1) = union(object.parts);
        let ucols = ux1 - ux0;
        let mut acc = vec![0.0f32; (uy1 - uy0) * ucols * 4];
        let mut acc_z = acc.clone();
        for (i, p) in object.parts.iter().enumerate() {
            let (y0, y1, x0, x1) = p.window;
            let (pw, ph) = (x1 - x0, y1 - y0);
            let mut layer = vec![0.0f32; pw * ph * 4];
            let mut zl = layer.clone();
            for y in y0..y1 {
                for x in x0..x1 {
                    let j = ((y - y0) * pw + x - x0) * 4;
                    let lab = label(y, x);
                    let zm = if lab == i as i32 { 1.0f32 } else { 0.0 };
                    let zw = if lab >= 0 {
                        source.depth[y * w + x]
                    } else {
                        0.0
                    };
                    let c = colour(y, x);
                    for k in 0..4 {
                        layer[j + k] = c[k] * zm;
                    }
                    zl[j] = zw * zm;
                    zl[j + 3] = zm;
                }
            }
            if p.blur {
                layer = box_blur(&layer, pw, ph, p.direction, p.length).unwrap();
                zl = box_blur(&zl, pw, ph, p.direction, p.length).unwrap();
            }
            for y in y0..y1 {
                for x in x0..x1 {
                    let j = ((y - y0) * pw + x - x0) * 4;
                    let a = ((y - uy0) * ucols + x - ux0) * 4;
                    for k in 0..4 {
                        acc[a + k] += layer[j + k];
                        acc_z[a + k] += zl[j + k];
                    }
                }
            }
        }
        let mut out = out.to_vec();
        let mut front = 0;
        for y in uy0..uy1 {
            for x in ux0..ux1 {
                let a = ((y - uy0) * ucols + x - ux0) * 4;
                let j = (y * w + x) * 4;
                let b = acc[a..a + 4].try_into().unwrap();
                let s = out[j..j + 4].try_into().unwrap();
                let z = layers.then(|| (acc_z[a], acc_z[a + 3], back_depth[y * w + x]));
                let (o, near) = composite_pixel(b, s, z);
                front += near as u64;
                out[j..j + 4].copy_from_slice(&o);
            }
        }
        (out, front)
    }

    fn image(n: usize, seed: usize, scale: f32) -> Vec<f32> {
        (0..n)
            .map(|i| ((i * 7919 + seed * 104_729) % 997) as f32 / 997.0 * scale)
            .collect()
    }

    #[test]
    fn matches_the_serial_steps_on_any_thread_count() {
        let (w, h) = (61, 47);
        // premultiplied colours (alpha the largest channel), depths from 1 to 4
        let mut rgba = image(w * h * 4, 1, 1.0);
        for p in rgba.chunks_mut(4) {
            p[3] = p.iter().cloned().fold(0.0, f32::max);
        }
        let out0 = image(w * h * 4, 2, 1.0);
        let depth: Vec<f32> = image(w * h, 3, 3.0).iter().map(|v| v + 1.0).collect();
        let back_depth: Vec<f32> = image(w * h, 4, 4.0).iter().map(|v| v + 0.5).collect();
        let pasted_win = (10, 30, 12, 40);
        let pasted = image(20 * 28 * 4, 5, 0.5);
        let win = (12, 28, 15, 37);
        // three groups and pixels of other objects (-1)
        let labels: Vec<i32> = (0..16 * 22)
            .map(|i: usize| ((i * 31) % 7) as i32 % 4 - 1)
            .collect();
        let parts = [
            CoveragePart {
                window: (5, 35, 3, 50),
                direction: [7.5, 2.0],
                length: 12.3,
                blur: true,
            },
            CoveragePart {
                window: (0, 40, 10, 44),
                direction: [-1.0, 6.0],
                length: 9.0,
                blur: true,
            },
            CoveragePart {
                window: (12, 28, 15, 37),
                direction: [0.3, 0.2],
                length: 0.4,
                blur: false,
            },
        ];
        let along = |direction, length, blur| {
            [CoveragePart {
                window: (8, 33, 4, 52),
                direction,
                length,
                blur,
            }]
        };
        // one group: oblique and vertical (the general path), along a row (blurred row by row),
        // along a row with no tap beside the pixel, not blurred (the row path unblurred)
        let (row, short) = (along([-9.0, 0.0], 17.0, true), along([3.0, 0.0], 1.5, true));
        let (vertical, still) = (along([0.0, 5.0], 11.0, true), along([0.3, 0.0], 0.3, false));
        let pasted = Some((pasted_win, &pasted[..]));
        // several groups, some along rows (summed row by row), one a box of one tap
        let mixed = [
            CoveragePart {
                window: (6, 36, 2, 55),
                direction: [12.0, -0.0],
                length: 21.0,
                blur: true,
            },
            parts[0],
            CoveragePart {
                window: (9, 31, 10, 44),
                direction: [1.0, 0.0],
                length: 1.2,
                blur: true,
            },
            parts[2],
        ];
        for (pasted, parts) in [
            (pasted, &mixed[..]),
            (None, &mixed[..]),
            (pasted, &parts[..]),
            (None, &parts[..]),
            (None, &parts[..1]),
            (pasted, &row[..]),
            (None, &row[..]),
            (pasted, &short[..]),
            (pasted, &vertical[..]),
            (pasted, &still[..]),
        ] {
            let source = CoverageSource {
                rgba: &rgba,
                pasted,
                depth: &depth,
            };
            let object = CoverageObject {
                window: win,
                labels: &labels,
                parts,
            };
            for layers in [false, true] {
                let (want, wf) = serial(&out0, &back_depth, (w, h), &source, &object, layers);
                // in place on the colour so far, and into an output of garbage from it
                for (threads, fresh) in [(1, false), (2, false), (1, true), (2, true)] {
                    let mut got = if fresh {
                        vec![f32::NAN; out0.len()]
                    } else {
                        out0.clone()
                    };
                    let back = fresh.then_some(&out0[..]);
                    let f = crate::on_threads(threads, || {
                        coverage_blur(
                            (&mut got, back),
                            &back_depth,
                            (w, h),
                            &source,
                            &object,
                            layers,
                        )
                    })
                    .unwrap();
                    assert_eq!(f, wf);
                    assert!(got
                        .iter()
                        .zip(&want)
                        .all(|(p, q)| p.to_bits() == q.to_bits()));
                }
                assert_eq!(wf > 0, layers, "the data has pixels in front with layers");
                assert!(want != out0, "the object changes the frame");
            }
        }
    }

    #[test]
    fn a_blurred_layer_with_nan_is_an_error_on_either_path() {
        let (w, h) = (9, 5);
        let mut rgba = vec![0.5f32; w * h * 4];
        rgba[(2 * w + 4) * 4] = f32::NAN;
        let depth = vec![1.0f32; w * h];
        let source = CoverageSource {
            rgba: &rgba,
            pasted: None,
            depth: &depth,
        };
        let labels = vec![0i32; 3 * 3];
        for (direction, blur, fails, groups) in [
            ([2.0, 0.0], true, true, 1),
            ([2.0, 1.0], true, true, 1),
            ([2.0, 0.0], false, false, 1),
            ([2.0, 0.0], true, true, 2),
            ([2.0, 1.0], true, true, 2),
            ([2.0, 0.0], false, false, 2),
        ] {
            let part = CoveragePart {
                window: (0, 5, 0, 9),
                direction,
                length: 4.0,
                blur,
            };
            let parts = [part, part];
            let object = CoverageObject {
                window: (1, 4, 3, 6),
                labels: &labels,
                parts: &parts[..groups],
            };
            let mut out = vec![0.0f32; w * h * 4];
            let got = coverage_blur((&mut out, None), &depth, (w, h), &source, &object, true);
            assert_eq!(got.is_err(), fails, "{direction:?} {blur}");
            if fails {
                assert!(got.unwrap_err().to_string().contains("NaN"));
            }
        }
    }

    #[test]
    fn bad_windows_and_shapes_are_errors() {
        let (w, h) = (6, 4);
        let (rgba, depth) = (vec![0.0f32; w * h * 4], vec![1.0f32; w * h]);
        let source = CoverageSource {
            rgba: &rgba,
            pasted: None,
            depth: &depth,
        };
        let labels = vec![0i32; 4];
        let part = |window| CoveragePart {
            window,
            direction: [1.0, 0.0],
            length: 2.0,
            blur: true,
        };
        let run = |win: Window, parts: &[CoveragePart], labels: &[i32]| {
            let mut out = rgba.clone();
            let object = CoverageObject {
                window: win,
                labels,
                parts,
            };
            coverage_blur((&mut out, None), &depth, (w, h), &source, &object, true)
        };
        assert!(run((1, 3, 2, 4), &[part((0, 4, 0, 6))], &labels).is_ok());
        let e = run((1, 3, 2, 7), &[part((0, 4, 0, 6))], &labels).unwrap_err();
        assert!(e.to_string().contains("window"), "{e}");
        let e = run((1, 3, 2, 4), &[part((0, 5, 0, 6))], &labels).unwrap_err();
        assert!(e.to_string().contains("parts"), "{e}");
        let e = run((1, 3, 2, 4), &[], &labels).unwrap_err();
        assert!(e.to_string().contains("parts"), "{e}");
        let e = run((1, 3, 2, 4), &[part((0, 4, 0, 6))], &labels[..3]).unwrap_err();
        assert!(e.to_string().contains("labels"), "{e}");
    }
}
