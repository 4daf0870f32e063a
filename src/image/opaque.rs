//! Opaque image blur (Kraus section 3.2, eq. 7) and image-based opaque motion blur (section 4.1):
//! a box blur of the premultiplied colours, the triangle-max glow of the alpha (eq. 10) with the
//! same radius, and the rescale `RGBA_sub = RGBA_blur * A_glow / A_blur`, optionally composited
//! over a base image (figure 6, moving foreground) or under it (figure 7, moving background).
//!
//! Where `A_blur <= ALPHA_EPS` the colour is 0 (no division by zero, no NaN); the opacity is
//! always `A_glow`, so the result never has less opacity than the input. Along an image row the
//! whole filter is one fused pass (running sums, glow, rescale, composite) per row.
use rayon::prelude::*;

use super::glow::{glow_row, GlowScratch};
use super::lines::{build_sheared, directional_at, plan, LinePlan, Live};
use super::opaque_row::{
    alpha_constant, alpha_range, alpha_span, box_finish, finish, premultiplied, Composite, Glow,
    RowJob,
};
use super::sheared_finish::{finish_row, Unshear};
use super::sheared_row::{filter_row, FilterScratch};
use super::{check_direction, check_image, check_premultiplied, filled, put4, simd, write_copy};
use crate::error::{Error, Result};
use std::mem::MaybeUninit;

/// From this many output floats (16 MiB, a 1280x720 frame and up) the rows are written with
/// non-temporal stores (`box_finish`'s `stream`): an image that size leaves the cache anyway.
const STREAM_FLOATS: usize = 4 << 20;

#[derive(Default)]
struct RowScratch {
    glow: GlowScratch,
    a: Vec<f32>,
    g: [Vec<f32>; 2],
}

/// Along rows, two rows at a time: each row is checked (finite source and base with alphas in [0, 1], the span of
/// non-zero alpha, constant alpha) while it is read into the cache, the pixels out of reach of
/// its alpha get the empty result (the base, or 0), and the rest one fused pass (running sums,
/// glow, eq. 7, composite; `opaque_row`), which runs the two rows side by side when their
/// spans agree. Returns false when a value is not finite or an alpha is outside [0, 1] (the
/// rows are then zeros).
fn rows_path(
    rgba: &[f32],
    base: &[f32],
    w: usize,
    r: usize,
    comp: Option<Composite>,
    out: &mut [MaybeUninit<f32>],
) -> bool {
    let simd = simd();
    let same = std::ptr::eq(rgba, base);
    let stream = out.len() >= STREAM_FLOATS;
    out.par_chunks_mut(2 * w * 4)
        .zip(rgba.par_chunks(2 * w * 4))
        .zip(base.par_chunks(2 * w * 4))
        .map_init(RowScratch::default, |s, ((o, src), b)| {
            let mut spans = [None; 2];
            let mut glows = [false; 2];
            let mut ok = true;
            for (k, (sr, br)) in src.chunks(w * 4).zip(b.chunks(w * 4)).enumerate() {
                let range = alpha_range(sr, simd);
                ok &= range.is_some() && (comp.is_none() || same || premultiplied(br, simd));
                if range.is_some_and(|(lo, hi)| lo == hi && lo > 0.0) {
                    // One alpha > 0 all along the row: it spans the row and is its own glow.
                    spans[k] = Some((0, w));
                    glows[k] = true;
                    continue;
                }
                spans[k] = alpha_span(sr, simd)
                    .map(|(lo, hi)| (lo.saturating_sub(r), (hi + r + 1).min(w)));
                if let Some((xa, xb)) = spans[k] {
                    glows[k] = alpha_constant(&sr[xa * 4..xb * 4], simd);
                    if !glows[k] {
                        s.a.clear();
                        s.a.extend(sr[xa * 4..xb * 4].chunks_exact(4).map(|px| px[3]));
                        s.g[k].resize(xb - xa, 0.0);
                        glow_row(&s.a, r, &mut s.g[k], &mut s.glow);
                    }
                }
            }
            if !ok {
                o.fill(MaybeUninit::new(0.0));
                return false;
            }
            let mut jobs = Vec::with_capacity(2);
            let rows = o
                .chunks_mut(w * 4)
                .zip(src.chunks(w * 4))
                .zip(b.chunks(w * 4));
            for (k, ((or, sr), br)) in rows.enumerate() {
                let (xa, xb) = spans[k].unwrap_or((w, w));
                let empty = |o: &mut [MaybeUninit<f32>], from: usize| match comp {
                    Some(_) => write_copy(o, &br[from..from + o.len()]),
                    None => o.fill(MaybeUninit::new(0.0)),
                };
                let (head, rest) = or.split_at_mut(xa * 4);
                empty(head, 0);
                empty(&mut rest[(xb - xa) * 4..], xb * 4);
                if xa < xb {
                    let glow = match glows[k] {
                        true => Glow::Const(sr[xa * 4 + 3]),
                        false => Glow::Row(&s.g[k]),
                    };
                    jobs.push(RowJob {
                        src: sr,
                        base: br,
                        out: or,
                        span: (xa, xb),
                        glow,
                    });
                }
            }
            box_finish(&mut jobs, w, r, comp, simd, stream);
            true
        })
        .reduce(|| true, |a, b| a & b)
}

/// An alpha's bounding box in pixels: columns `x0..=x1`, rows `y0..=y1`.
type BBox = (usize, usize, usize, usize);

/// One streaming pass over the image (and the base when `composite`, unless it is the image):
/// whether every value is finite with alphas in [0, 1], and the box of the non-zero alphas
/// (`None`: none).
fn scan(rgba: &[f32], base: &[f32], w: usize, composite: bool) -> (bool, Option<BBox>) {
    let simd = simd();
    let check_base = composite && !std::ptr::eq(rgba, base);
    let join = |a: (bool, Option<BBox>), b: (bool, Option<BBox>)| {
        let bbox = match (a.1, b.1) {
            (Some(a), Some(b)) => Some((a.0.min(b.0), a.1.max(b.1), a.2.min(b.2), a.3.max(b.3))),
            (a, b) => a.or(b),
        };
        (a.0 & b.0, bbox)
    };
    rgba.par_chunks(w * 4)
        .zip(base.par_chunks(w * 4))
        .enumerate()
        .map(|(y, (src, b))| {
            let ok = premultiplied(src, simd) && (!check_base || premultiplied(b, simd));
            (ok, alpha_span(src, simd).map(|(lo, hi)| (lo, hi, y, y)))
        })
        .reduce(|| (true, None), join)
}

/// The crop `(cx0, cx1, cy0, cy1)` (half-open) that can receive non-zero alpha from `bbox`:
/// the box grown by two filter reaches along the blur (`p.radius`) and across it (the shear),
/// clamped to the `w` x `h` image.
fn crop_box(bbox: BBox, p: &LinePlan, w: usize, h: usize) -> BBox {
    let (x0, x1, y0, y1) = bbox;
    let major = 2 * p.radius + 2;
    let minor = (2.0 * p.radius as f64 * p.slope.abs()).ceil() as usize + 2;
    let (mx, my) = if p.transpose {
        (minor, major)
    } else {
        (major, minor)
    };
    let (cx0, cx1) = (x0.saturating_sub(mx), (x1 + 1 + mx).min(w));
    let (cy0, cy1) = (y0.saturating_sub(my), (y1 + 1 + my).min(h));
    (cx0, cx1, cy0, cy1)
}

/// Any other direction: the filter runs on the crop that can receive non-zero alpha (the
/// alpha's bounding box grown by two filter reaches), transposed and/or sheared; then each
/// output row is written once: the empty result (the base, or 0) outside the crop, eq. 7 and
/// the composite inside. Returns false when a value is not finite or an alpha is outside [0, 1]
/// (the output is then zeros).
fn crop_path(
    rgba: &[f32],
    base: &[f32],
    w: usize,
    h: usize,
    p: &LinePlan,
    comp: Option<Composite>,
    out: &mut [MaybeUninit<f32>],
) -> Result<bool> {
    let simd = simd();
    let (ok, bbox) = scan(rgba, base, w, comp.is_some());
    if !ok {
        out.par_chunks_mut(w * 4)
            .for_each(|o| o.fill(MaybeUninit::new(0.0)));
        return Ok(false);
    }
    // The empty result of output row `y`, columns `xa .. xb`.
    let empty = |y: usize, xa: usize, xb: usize, o: &mut [MaybeUninit<f32>]| match comp {
        Some(_) => write_copy(
            &mut o[xa * 4..xb * 4],
            &base[(y * w + xa) * 4..(y * w + xb) * 4],
        ),
        None => o[xa * 4..xb * 4].fill(MaybeUninit::new(0.0)),
    };
    let Some((x0, x1, y0, y1)) = bbox else {
        out.par_chunks_mut(w * 4)
            .enumerate()
            .for_each(|(y, o)| empty(y, 0, w, o));
        return Ok(true);
    };
    let r = p.radius;
    let (cx0, cx1, cy0, cy1) = crop_box((x0, x1, y0, y1), p, w, h);
    let (cw, ch) = (cx1 - cx0, cy1 - cy0);
    // The crop, copied unless it is the whole image.
    let mut copy = None;
    if cw < w || ch < h {
        let mut c = super::pool::take_for("rgba", cw * ch * 4)?;
        c.par_chunks_mut(cw * 4).enumerate().for_each(|(k, row)| {
            let y = cy0 + k;
            row.copy_from_slice(&rgba[(y * w + cx0) * 4..(y * w + cx1) * 4]);
        });
        copy = Some(c);
    }
    let crop = copy.as_deref().unwrap_or(rgba);
    let offset = if p.transpose { cy0 } else { cx0 } as f64;
    let live = [x0 - cx0, x1 - cx0, y0 - cy0, y1 - cy0];
    let filter = |src: &[f32], n: usize, o: &mut [f32], s: &mut FilterScratch| -> bool {
        filter_row(src, n, r, o, s, simd)
    };
    // Output row `y`: the empty result outside the crop, `inside(k, o, scratch)` for crop row
    // `k` (`scratch`: a buffer of the thread).
    type Inside<'a> = dyn Fn(usize, &mut [MaybeUninit<f32>], &mut Vec<f32>) + Sync + 'a;
    let mut rows = |inside: &Inside| {
        out.par_chunks_mut(w * 4)
            .enumerate()
            .for_each_init(Vec::new, |s, (y, o)| {
                if y < cy0 || y >= cy1 {
                    return empty(y, 0, w, o);
                }
                empty(y, 0, cx0, o);
                empty(y, cx1, w, o);
                inside(y - cy0, &mut o[cx0 * 4..cx1 * 4], s);
            })
    };
    if p.slope != 0.0 && !p.transpose {
        // Shear and filter, then shear back straight into the output, row by row.
        let sh = build_sheared::<4, 5, FilterScratch>(
            "rgba",
            crop,
            cw,
            ch,
            p.slope,
            offset,
            Live::Box(live),
            &filter,
        )?;
        let u = Unshear::new(&sh, cw, ch);
        rows(&|k, o, s| {
            let at = ((cy0 + k) * w + cx0) * 4;
            let (alpha, b) = (&rgba[at..at + cw * 4], &base[at..at + cw * 4]);
            finish_row(&sh, &u, k, alpha, b, o, comp, simd, s);
        });
        super::pool::give(sh.data);
    } else {
        let five = directional_at::<4, 5, FilterScratch>(
            "rgba",
            crop,
            cw,
            ch,
            p,
            offset,
            Live::Box(live),
            filter,
        )?;
        // Eq. 7 and the composite of crop row `k` (five values a pixel: blur RGBA and glow).
        let oblique = p.slope != 0.0;
        rows(&|k, o, _| {
            let f5 = &five[k * cw * 5..(k + 1) * cw * 5];
            let at = ((cy0 + k) * w + cx0) * 4;
            for x in 0..cw {
                let f = &f5[x * 5..x * 5 + 5];
                let i = at + x * 4;
                let g = if oblique { f[4].max(rgba[i + 3]) } else { f[4] };
                put4(
                    o,
                    x,
                    finish([f[0], f[1], f[2], f[3]], g, &base[i..i + 4], comp),
                );
            }
        });
        super::pool::give(five);
    }
    if let Some(c) = copy {
        super::pool::give(c);
    }
    Ok(true)
}

/// One opaque blur's inputs: the `(h, w, 4)` image, the base it is composited with (`rgba`
/// itself when `None`), the direction and length of the blur in pixels, and the composite
/// (`None`: no compositing).
#[derive(Clone, Copy)]
struct Blur<'a> {
    rgba: &'a [f32],
    base: Option<&'a [f32]>,
    w: usize,
    h: usize,
    direction: [f32; 2],
    length: f32,
    comp: Option<Composite>,
}

impl Blur<'_> {
    /// The image and direction checks every opaque blur makes before it allocates.
    fn check(&self) -> Result<()> {
        check_image("rgba", self.rgba, self.w, self.h, 4)?;
        if let Some(b) = self.base {
            check_image("base", b, self.w, self.h, 4)?;
        }
        check_direction(self.direction, self.length, "length")
    }

    /// The blur in a new image, the inputs checked first ([`Blur::check`]).
    fn new_image(&self) -> Result<Vec<f32>> {
        self.check()?;
        let mut ok = Ok(());
        let out = filled(self.w * self.h * 4, |out| ok = self.write(out));
        ok.map(|()| out)
    }

    /// The blur written into every element of `out` (`(h, w, 4)`); the inputs already checked
    /// ([`Blur::check`]). On an error (an image not premultiplied) `out`'s contents are
    /// unspecified.
    fn write(&self, out: &mut [MaybeUninit<f32>]) -> Result<()> {
        let (rgba, w, comp) = (self.rgba, self.w, self.comp);
        let base = self.base.unwrap_or(rgba);
        let p = plan(self.direction, self.length * 0.5);
        if p.is_none() {
            check_premultiplied("rgba", rgba, 4)?;
            check_premultiplied("base", base, 4)?;
        }
        let ok = match p {
            Some(p) if !p.transpose && p.slope == 0.0 => {
                rows_path(rgba, base, w, p.radius, comp, out)
            }
            Some(p) => crop_path(rgba, base, w, self.h, &p, comp, out)?,
            None => {
                out.par_chunks_mut(4)
                    .zip(rgba.par_chunks(4))
                    .zip(base.par_chunks(4))
                    .for_each(|((o, px), b)| {
                        put4(o, 0, finish([px[0], px[1], px[2], px[3]], px[3], b, comp))
                    });
                true
            }
        };
        if !ok {
            check_premultiplied("rgba", rgba, 4)?;
            check_premultiplied("base", base, 4)?;
        }
        Ok(())
    }
}

/// Opaque image blur of a `(h, w, 4)` premultiplied image along `direction` over `length` pixels:
/// box blur, glow of the same radius, eq. 7. No compositing.
pub fn opaque_blur(
    rgba: &[f32],
    w: usize,
    h: usize,
    direction: [f32; 2],
    length: f32,
) -> Result<Vec<f32>> {
    Blur {
        rgba,
        base: None,
        w,
        h,
        direction,
        length,
        comp: None,
    }
    .new_image()
}

/// Opaque motion blur (figures 6 and 7): `opaque_blur(rgba)` composited `mode` the base image
/// (`rgba` itself when `base` is `None`).
pub fn opaque_motion_blur(
    rgba: &[f32],
    base: Option<&[f32]>,
    w: usize,
    h: usize,
    direction: [f32; 2],
    length: f32,
    mode: Composite,
) -> Result<Vec<f32>> {
    Blur {
        rgba,
        base,
        w,
        h,
        direction,
        length,
        comp: Some(mode),
    }
    .new_image()
}

/// [`opaque_motion_blur`] written into `out` (`(h, w, 4)`, every element overwritten): the same
/// values, without a new image (and, for a frame-sized one, without the fresh pages the system
/// must clear first). On an error `out`'s contents are unspecified.
#[allow(clippy::too_many_arguments)]
pub fn opaque_motion_blur_into(
    rgba: &[f32],
    base: Option<&[f32]>,
    w: usize,
    h: usize,
    direction: [f32; 2],
    length: f32,
    mode: Composite,
    out: &mut [f32],
) -> Result<()> {
    let blur = Blur {
        rgba,
        base,
        w,
        h,
        direction,
        length,
        comp: Some(mode),
    };
    blur.check()?;
    if out.len() != w * h * 4 {
        return Err(Error::shape("out", "must be (H, W, 4) like rgba"));
    }
    // SAFETY: MaybeUninit<f32> has f32's layout, and the writer only stores initialised values.
    let out = unsafe { &mut *(out as *mut [f32] as *mut [MaybeUninit<f32>]) };
    blur.write(out)
}
