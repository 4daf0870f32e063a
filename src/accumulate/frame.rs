//! The accumulation buffer's frame in one call: every time sample rasterized by the
//! [`Painter`] and summed with its weight, without returning to the caller in between.
//!
//! Still camera ([`accumulate_still`]): the static objects are a layer kept by the caller;
//! each sample draws only the moving objects (the painter's), inside the pixel rectangle that
//! bounds them at that time (a rigid object's transformed bounding box, a deforming one's
//! vertices), through a projection of that rectangle alone. The frame's window is the union of
//! the rectangles; per sample the moving layer M_i is summed where it is in front of the static
//! surface, and the static layer S is composited once after the last sample, which equals
//! `sum_i w_i (M_i over S)` for an opaque static layer. With a transparent static layer each
//! sample is composited with it by depth before it is summed. Depth and ids are those of the
//! sample nearest the reference time, composited with the static layer.
//!
//! Moving camera ([`accumulate_moving`]): every sample is a whole frame of every object, seen
//! by that sample's view.
//!
//! Samples are rasterized one after the other (each parallel over its faces and tiles) and
//! summed in sample order.
//!
//! The rectangles and projections are the numpy expressions of the per-sample loop in the same
//! order (see [`crate::motion`]'s fixed-order arithmetic; the loop is the tests' serial twin),
//! and the sums are the kernels of `kernels.rs` in sample order, so the frame is the same bit
//! for bit, for any thread count.
use super::kernels::{accumulate, accumulate_limited, composite, over, Limit, Rect};
use super::painter::Painter;
use crate::budget::Need;
use crate::error::{Error, Result};
use crate::frame::{Frame, Layer};
use crate::motion::{linear_part, mat4_mul, place, row_times, Mat4, IDENTITY4};

/// The shutter samples of a frame.
#[derive(Debug, Clone, Copy)]
pub struct Samples<'a> {
    /// Shutter times (N,), in [0, 1].
    pub times: &'a [f64],
    /// Weights (N,), summed as float32 (finite).
    pub weights: &'a [f64],
    /// The sample whose depth and ids the frame keeps (nearest the reference time).
    pub reference: usize,
}

impl Samples<'_> {
    fn check(&self) -> Result<()> {
        let n = self.times.len();
        if n == 0 || self.weights.len() != n {
            return Err(Error::shape("weights", "one weight per time, at least one"));
        }
        if self.times.iter().any(|t| !(0.0..=1.0).contains(t)) {
            return Err(Error::value("times", "must lie in [0, 1]"));
        }
        if self.weights.iter().any(|w| !(*w as f32).is_finite()) {
            return Err(Error::value("weights", "must be finite"));
        }
        if self.reference >= n {
            return Err(Error::value("reference", format!("must be < {n}")));
        }
        Ok(())
    }
}

/// The camera of a still frame (supersampled): matrices row-major, size in samples.
#[derive(Debug, Clone, Copy)]
pub struct StillCamera {
    /// World-to-camera.
    pub view: Mat4,
    /// Camera-to-clip.
    pub projection: Mat4,
    /// `projection @ view`, as the caller computed it (the rectangles use it).
    pub view_projection: Mat4,
    /// Width in samples.
    pub width: usize,
    /// Height in samples.
    pub height: usize,
    /// Samples per pixel along each axis (the window is aligned to it).
    pub aa: usize,
}

/// An accumulated frame (or its window) of the samples at `window` (x0, y0, x1, y1) of the
/// image: the weighted sum's premultiplied `rgba`, the reference sample's `depth` and `ids`.
#[derive(Debug, Clone)]
pub struct Accumulated {
    /// The sum and the reference sample's depth and ids (no velocity), the window's size.
    pub frame: Frame,
    /// The samples' rectangle in the image (the whole image with a moving camera).
    pub window: [usize; 4],
    /// Rasterizer passes over the objects (one per sample drawn).
    pub draw_calls: usize,
}

/// The projection that renders only the rectangle `w` (x0, y0, x1, y1) of a `width` x
/// `height` image into an image of its size, with the same pixel centres.
pub fn window_projection(projection: &Mat4, width: usize, height: usize, w: [usize; 4]) -> Mat4 {
    let (wf, hf) = (width as f64, height as f64);
    let [x0, y0, x1, y1] = w.map(|v| v as f64);
    let (xl, xr) = (2.0 * x0 / wf - 1.0, 2.0 * x1 / wf - 1.0);
    let (yt, yb) = (1.0 - 2.0 * y0 / hf, 1.0 - 2.0 * y1 / hf);
    let mut s = IDENTITY4;
    s[0][0] = 2.0 / (xr - xl);
    s[0][3] = -(xr + xl) / (xr - xl);
    s[1][1] = 2.0 / (yt - yb);
    s[1][3] = -(yt + yb) / (yt - yb);
    mat4_mul(&s, projection)
}

/// The pixel rectangle (x0, y0, x1, y1) of a `width` x `height` image holding `points` seen
/// through `vp` (world to clip), grown by a pixel and clamped; the whole image when a point is
/// not in front of the camera; None when they are off the image.
pub fn pixel_rect(
    vp: &Mat4,
    points: &[[f64; 3]],
    width: usize,
    height: usize,
) -> Option<[usize; 4]> {
    let l = linear_part(vp);
    let t = [vp[0][3], vp[1][3], vp[2][3]];
    let last = [vp[3][0], vp[3][1], vp[3][2]];
    let (wf, hf) = (width as f64, height as f64);
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in points {
        let c = place(&l, &t, p);
        let w = row_times(p, &last) + vp[3][3];
        if w <= 1e-9 {
            return Some([0, 0, width, height]);
        }
        let x = (c[0] / w + 1.0) * 0.5 * wf;
        let y = (1.0 - c[1] / w) * 0.5 * hf;
        lo = [lo[0].min(x), lo[1].min(y)];
        hi = [hi[0].max(x), hi[1].max(y)];
    }
    let x0 = (lo[0].floor() - 1.0).max(0.0);
    let y0 = (lo[1].floor() - 1.0).max(0.0);
    let x1 = (hi[0].ceil() + 1.0).min(wf);
    let y1 = (hi[1].ceil() + 1.0).min(hf);
    if !(x0 < x1 && y0 < y1) {
        return None;
    }
    Some([x0, y0, x1, y1].map(|v| v as usize))
}

/// Per sample time, the pixel rectangle of the painter's objects (rigid ones by their
/// transformed bounding box, deforming ones by their vertices), or None when off the image.
pub fn sample_rects(
    painter: &Painter,
    camera: &StillCamera,
    times: &[f64],
) -> Vec<Option<[usize; 4]>> {
    let corners: Vec<Option<[[f64; 3]; 8]>> = painter
        .objects()
        .iter()
        .map(|o| (!o.motion.as_ref().is_some_and(|m| m.is_deforming())).then(|| o.box_corners()))
        .collect();
    times
        .iter()
        .map(|&t| {
            let mut pts: Vec<[f64; 3]> = Vec::new();
            for (o, c) in painter.objects().iter().zip(&corners) {
                match c {
                    Some(c) => {
                        let m = o.placement(t);
                        let (l, tr) = (linear_part(&m), [m[0][3], m[1][3], m[2][3]]);
                        pts.extend(c.iter().map(|p| place(&l, &tr, p)));
                    }
                    None => pts.extend(o.world_vertices(t)),
                }
            }
            if pts.is_empty() {
                return None;
            }
            pixel_rect(&camera.view_projection, &pts, camera.width, camera.height)
        })
        .collect()
}

/// A rectangle `[x0, y0, x1, y1]` cut out of a row-major buffer `stride` entries wide with
/// `channels` values each.
fn crop<T: Copy>(data: &[T], stride: usize, channels: usize, w: [usize; 4]) -> Vec<T> {
    let mut out = Vec::with_capacity((w[2] - w[0]) * (w[3] - w[1]) * channels);
    for y in w[1]..w[3] {
        out.extend_from_slice(
            &data[(y * stride + w[0]) * channels..(y * stride + w[2]) * channels],
        );
    }
    out
}

/// `acc += weight * add`, float32, element by element.
fn add_weighted(acc: &mut [f32], add: &[f32], weight: f32) {
    for (a, b) in acc.iter_mut().zip(add) {
        *a += weight * *b;
    }
}

/// The still-camera frame (see the module doc): the painter's (moving) objects at every
/// sample over `background`, the static layer of `camera`'s size (`opaque` when every static
/// object is). None when the objects are off the image at every sample.
pub fn accumulate_still(
    painter: &Painter,
    camera: &StillCamera,
    samples: Samples<'_>,
    background: Layer<'_>,
    opaque: bool,
) -> Result<Option<Accumulated>> {
    let mut out = accumulate_still_parts(painter, camera, &[samples], background, opaque, None)?;
    Ok(out.pop().flatten())
}

/// [`accumulate_still`] of each of `parts` (an accumulation's halves or quarters), the same
/// frames bit for bit, sharing what they can: the static layer is cropped once for the union
/// of the parts' windows, and only part `keep` (every part when None) gets the reference
/// sample's depth and ids; the others' `depth` and `ids` are empty. Each part's frame covers
/// its own window, and whether its window holds a static surface is decided there.
pub fn accumulate_still_parts(
    painter: &Painter,
    camera: &StillCamera,
    parts: &[Samples<'_>],
    background: Layer<'_>,
    opaque: bool,
    keep: Option<usize>,
) -> Result<Vec<Option<Accumulated>>> {
    for samples in parts {
        check_still(camera, samples, &background)?;
    }
    let rects: Vec<_> = parts
        .iter()
        .map(|s| sample_rects(painter, camera, s.times))
        .collect();
    let wins: Vec<_> = rects.iter().map(|r| union_window(r, camera)).collect();
    let Some(all) = union_window(&wins, camera) else {
        return Ok(parts.iter().map(|_| None).collect());
    };
    let (uw, uh) = (all[2] - all[0], all[3] - all[1]);
    // The union's crop of the static layer (20 bytes a sample), each part's sum (16), the
    // reference sample's depth and ids (8) and a sample's layer (24; the rasterizer checks its
    // own frame), before any is allocated.
    Need::new("accumulation")
        .add(
            &[("window width", uw as u64), ("window height", uh as u64)],
            52 + 16 * parts.len() as u64,
        )?
        .check()?;
    let shared = Shared {
        painter,
        camera,
        background,
        opaque,
        all,
        base_rgba: crop(background.rgba, camera.width, 4, all),
        base_depth: crop(background.depth, camera.width, 1, all),
    };
    let mut out = Vec::with_capacity(parts.len());
    for (p, samples) in parts.iter().enumerate() {
        out.push(match wins[p] {
            None => None,
            Some(win) => {
                let kept = keep.is_none_or(|k| k == p);
                Some(shared.part(samples, &rects[p], win, kept)?)
            }
        });
    }
    Ok(out)
}

/// What the parts of [`accumulate_still_parts`] share: the painter and camera, the static
/// layer and its crop to the union `all` of the parts' windows.
struct Shared<'a> {
    painter: &'a Painter,
    camera: &'a StillCamera,
    background: Layer<'a>,
    opaque: bool,
    all: [usize; 4],
    base_rgba: Vec<f32>,
    base_depth: Vec<f32>,
}

/// One part's sum as it is made: its window's accumulator, the reference sample's depth and
/// ids (when `kept`), and its own crops of a transparent static layer.
struct PartSum<'s> {
    win: [usize; 4],
    acc: Vec<f32>,
    kept: bool,
    keep_depth: Vec<f32>,
    keep_ids: Vec<i32>,
    own: Option<Own>,
    limit: Option<Limit<'s>>,
}

/// A part's own crops of a transparent static layer (rgba, depth, ids) and the buffers each
/// sample is composited with them in, refilled from the crops for every sample (one
/// allocation a part, not three a sample).
struct Own {
    crop: (Vec<f32>, Vec<f32>, Vec<i32>),
    scratch: (Vec<f32>, Vec<f32>, Vec<i32>),
}

impl Shared<'_> {
    /// The part's window inside the union's crop.
    fn inside(&self, win: [usize; 4]) -> Rect {
        Rect {
            x0: win[0] - self.all[0],
            y0: win[1] - self.all[1],
            width: win[2] - win[0],
            height: win[3] - win[1],
            stride: self.all[2] - self.all[0],
        }
    }

    /// One part's frame over its window `win`: its `samples` (drawn at `rects`) summed, the
    /// static layer composited once after the last when it is opaque.
    fn part(
        &self,
        samples: &Samples<'_>,
        rects: &[Option<[usize; 4]>],
        win: [usize; 4],
        kept: bool,
    ) -> Result<Accumulated> {
        let inside = self.inside(win);
        let has_static =
            rows_in(&self.base_depth, 1, inside).any(|r| r.iter().any(|d| d.is_finite()));
        let mut sum = self.part_sum(win, kept, has_static);
        let mut draw_calls = 0;
        for (i, rect) in rects.iter().enumerate() {
            draw_calls += usize::from(self.add_sample(&mut sum, samples, i, *rect)?);
        }
        if has_static && self.opaque {
            // `over` of the window's crop, row by row
            let ww = win[2] - win[0];
            for (a, u) in sum
                .acc
                .chunks_exact_mut(4 * ww)
                .zip(rows_in(&self.base_rgba, 4, inside))
            {
                over(a, u)?;
            }
        }
        Ok(Accumulated {
            frame: Frame {
                width: (win[2] - win[0]) as u32,
                height: (win[3] - win[1]) as u32,
                rgba: sum.acc,
                depth: sum.keep_depth,
                ids: sum.keep_ids,
                velocity: None,
                exposure: None,
            },
            window: win,
            draw_calls,
        })
    }

    /// A part's empty sum: its accumulator, the reference's depth and ids (when `kept`), the
    /// own crops of a transparent static layer (a sample is composited with it before it is
    /// summed) and the depth limit of an opaque one.
    fn part_sum(&self, win: [usize; 4], kept: bool, has_static: bool) -> PartSum<'_> {
        let (iw, bg) = (self.camera.width, &self.background);
        let exact_sum = !has_static || self.opaque;
        let (ww, wh) = (win[2] - win[0], win[3] - win[1]);
        let (keep_depth, keep_ids) = if kept {
            (crop(bg.depth, iw, 1, win), crop(bg.ids, iw, 1, win))
        } else {
            (Vec::new(), Vec::new())
        };
        let own = (!exact_sum).then(|| {
            let crop = (
                crop(bg.rgba, iw, 4, win),
                crop(bg.depth, iw, 1, win),
                crop(bg.ids, iw, 1, win),
            );
            Own {
                scratch: crop.clone(),
                crop,
            }
        });
        let inside = self.inside(win);
        let limit = has_static.then_some(Limit {
            data: &self.base_depth,
            stride: inside.stride,
            x0: inside.x0,
            y0: inside.y0,
        });
        PartSum {
            win,
            acc: vec![0.0f32; 4 * ww * wh],
            kept,
            keep_depth,
            keep_ids,
            own,
            limit,
        }
    }

    /// Sample `i` of `samples` (drawn at `rect`, None when off the image) added to `sum` with
    /// its weight; whether it was drawn.
    fn add_sample(
        &self,
        sum: &mut PartSum<'_>,
        samples: &Samples<'_>,
        i: usize,
        rect: Option<[usize; 4]>,
    ) -> Result<bool> {
        let w = samples.weights[i] as f32;
        let Some(r) = rect else {
            if let Some(own) = &sum.own {
                add_weighted(&mut sum.acc, &own.crop.0, w);
            }
            return Ok(false);
        };
        let (iw, ih) = (self.camera.width, self.camera.height);
        let proj = window_projection(&self.camera.projection, iw, ih, r);
        let (lw, lh) = ((r[2] - r[0]) as u32, (r[3] - r[1]) as u32);
        let layer = self
            .painter
            .layer(samples.times[i], &self.camera.view, &proj, lw, lh)?;
        let win = sum.win;
        let sub = Rect {
            x0: r[0] - win[0],
            y0: r[1] - win[1],
            width: r[2] - r[0],
            height: r[3] - r[1],
            stride: win[2] - win[0],
        };
        if i == samples.reference && sum.kept {
            composite_depth_ids(
                &layer.depth,
                &layer.ids,
                &mut sum.keep_depth,
                &mut sum.keep_ids,
                sub,
            );
        }
        match &mut sum.own {
            None => accumulate_limited(&mut sum.acc, &layer.rgba, &layer.depth, sum.limit, w, sub)?,
            Some(Own { crop, scratch }) => {
                let (full, depth, ids) = scratch;
                full.copy_from_slice(&crop.0);
                depth.copy_from_slice(&crop.1);
                ids.copy_from_slice(&crop.2);
                composite(&layer.rgba, &layer.depth, &layer.ids, full, depth, ids, sub)?;
                add_weighted(&mut sum.acc, full, w);
            }
        }
        Ok(true)
    }
}

/// The rows of `rect` in `data` (`rect.stride` samples of `c` values a row).
fn rows_in(data: &[f32], c: usize, rect: Rect) -> impl Iterator<Item = &[f32]> {
    (0..rect.height).map(move |y| {
        let at = ((rect.y0 + y) * rect.stride + rect.x0) * c;
        &data[at..at + rect.width * c]
    })
}

/// The depth and ids of [`composite`] alone: where layer `a` (covering `rect`) has a surface
/// no farther than `b`'s, its depth and id.
fn composite_depth_ids(
    a_depth: &[f32],
    a_ids: &[i32],
    depth: &mut [f32],
    ids: &mut [i32],
    rect: Rect,
) {
    for ry in 0..rect.height {
        let row = (rect.y0 + ry) * rect.stride + rect.x0;
        for i in 0..rect.width {
            let (s, d) = (ry * rect.width + i, row + i);
            let ad = a_depth[s];
            if ad != f32::INFINITY && ad <= depth[d] {
                depth[d] = ad;
                ids[d] = a_ids[s];
            }
        }
    }
}

/// The checks of [`accumulate_still`]'s inputs (errors name `times`/`weights`, `background`
/// or `aa`).
fn check_still(camera: &StillCamera, samples: &Samples<'_>, background: &Layer<'_>) -> Result<()> {
    samples.check()?;
    if (background.width, background.height) != (camera.width, camera.height) {
        return Err(Error::shape(
            "background",
            "one entry per sample of the image expected",
        ));
    }
    background.check_lengths("background")?;
    if camera.aa == 0 {
        return Err(Error::value("aa", "must be >= 1"));
    }
    Ok(())
}

/// The union of the samples' drawn rectangles `[x0, y0, x1, y1]` (sample units), grown to
/// whole pixels of `camera.aa` samples and clamped to the image; `None` when no sample drew.
fn union_window(rects: &[Option<[usize; 4]>], camera: &StillCamera) -> Option<[usize; 4]> {
    let mut found = rects.iter().flatten();
    let first = *found.next()?;
    let win = found.fold(first, |a, r| {
        [
            a[0].min(r[0]),
            a[1].min(r[1]),
            a[2].max(r[2]),
            a[3].max(r[3]),
        ]
    });
    let aa = camera.aa;
    Some([
        win[0] / aa * aa,
        win[1] / aa * aa,
        camera.width.min(win[2].div_ceil(aa) * aa),
        camera.height.min(win[3].div_ceil(aa) * aa),
    ])
}

/// The moving-camera frame (see the module doc): the painter's objects at every sample, seen
/// through that sample's `views` (N, row-major) and `projection`, `width` x `height` samples.
pub fn accumulate_moving(
    painter: &Painter,
    views: &[Mat4],
    projection: &Mat4,
    width: usize,
    height: usize,
    samples: Samples<'_>,
) -> Result<Accumulated> {
    samples.check()?;
    if views.len() != samples.times.len() {
        return Err(Error::shape("views", "one view per time expected"));
    }
    // The sum, the reference sample's layer and the sample being added (24 bytes a sample
    // each), before any is allocated.
    Need::new("accumulation")
        .add(&[("width", width as u64), ("height", height as u64)], 72)?
        .check()?;
    let mut acc: Vec<f32> = Vec::new();
    let mut keep: Option<Frame> = None;
    let draw = |i: usize| -> Result<Frame> {
        painter.layer(
            samples.times[i],
            &views[i],
            projection,
            width as u32,
            height as u32,
        )
    };
    for (i, layer) in (0..samples.times.len()).map(|i| (i, draw(i))) {
        let w = samples.weights[i] as f32;
        let mut layer = layer?;
        if i == 0 {
            // The first layer's colour becomes the sum in place (the reference keeps only its
            // depth and ids): a fresh frame-sized buffer is page-faulted in 4 KiB pages when
            // it is above glibc's largest mmap threshold (32 MiB; a 4K frame's colour: 127 MiB).
            acc = std::mem::take(&mut layer.rgba);
            acc.iter_mut().for_each(|x| *x *= w);
        } else {
            let rows = Rect {
                x0: 0,
                y0: 0,
                width,
                height,
                stride: width,
            };
            accumulate(&mut acc, &layer.rgba, &layer.depth, None, w, rows)?;
        }
        if i == samples.reference {
            keep = Some(layer);
        }
    }
    let keep = keep.expect("the reference sample was drawn");
    Ok(Accumulated {
        frame: Frame { rgba: acc, ..keep },
        window: [0, 0, width, height],
        draw_calls: samples.times.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accumulate::PaintObject;
    use crate::raster::Shading;

    fn perspective() -> Mat4 {
        // pyrender's projection for yfov 0.7, aspect 4/3, znear 0.5, zfar 30
        let t = (0.35f64).tan();
        let mut p = [[0.0; 4]; 4];
        p[0][0] = 1.0 / (4.0 / 3.0 * t);
        p[1][1] = 1.0 / t;
        p[2][2] = 30.5 / -29.5;
        p[2][3] = 30.0 / -29.5;
        p[3][2] = -1.0;
        p
    }

    #[test]
    fn the_whole_window_keeps_the_projection() {
        let p = perspective();
        assert_eq!(window_projection(&p, 64, 48, [0, 0, 64, 48]), p);
        // a window's pixel centres are the image's: the window's left edge maps to -1
        let w = window_projection(&p, 64, 48, [16, 8, 48, 40]);
        let x_ndc = |m: &Mat4, x: f64| m[0][0] * x + m[0][3];
        let full = x_ndc(&p, 0.1);
        assert!(((full + 1.0) * 32.0 - 16.0 - (x_ndc(&w, 0.1) + 1.0) * 16.0).abs() < 1e-12);
    }

    #[test]
    fn rects_bound_the_points_and_clamp_to_the_image() {
        let mut vp = perspective();
        vp[2][3] -= 5.0; // the camera 5 units back along +z
        vp[3][3] += 5.0;
        let r = pixel_rect(&vp, &[[0.0, 0.0, 0.0]], 64, 48).unwrap();
        assert_eq!(r, [31, 23, 33, 25]); // the centre pixel, grown by one
        assert_eq!(
            pixel_rect(&vp, &[[0.0, 0.0, 6.0]], 64, 48),
            Some([0, 0, 64, 48])
        ); // behind
        assert_eq!(pixel_rect(&vp, &[[100.0, 0.0, 0.0]], 64, 48), None); // off the image
        let cube = PaintObject {
            id: 0,
            shading: Shading::Flat,
            vertices: vec![[-1.0, -2.0, -3.0], [1.0, 2.0, 3.0], [0.0, 0.0, 0.0]],
            faces: vec![[0, 1, 2]],
            rgba: vec![[1.0; 4]],
            normals: None,
            motion: None,
        };
        let c = cube.box_corners();
        assert_eq!(c[0], [-1.0, -2.0, -3.0]);
        assert_eq!(c[1], [-1.0, -2.0, 3.0]);
        assert_eq!(c[7], [1.0, 2.0, 3.0]);
    }
}
