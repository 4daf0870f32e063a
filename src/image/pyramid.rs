//! Pyramid blur and pyramid glow (Kraus section 3.2; Strengert, Kraus and Ertl 2006).
//!
//! Analysis: each level halves the size (`ceil(n / 2)`, so any size works, not only powers of
//! two) with a 4x4 box: coarse pixel `i` averages fine pixels `2i - 1 ..= 2i + 2` on each axis
//! (zero outside). Synthesis: a biquadratic B-spline expansion, fine pixel `2i` is
//! `3/4 c[i] + 1/4 c[i - 1]` and fine pixel `2i + 1` is `3/4 c[i] + 1/4 c[i + 1]` on each axis.
//! The blur expands the top level down to full size; the glow shares the analysis pyramid and
//! synthesises `A_syn = A_exp + A_ana - A_exp A_ana` (eqs. 8-9) at every level, so it never
//! lowers alpha. The opaque pyramid blur rescales the blur to the glow (eq. 7).
use rayon::prelude::*;

use super::{check_finite, check_image, check_premultiplied, ALPHA_EPS};
use crate::error::{Error, Result};

/// Most pyramid levels accepted (a 65536-pixel side is 1 pixel after 16 levels).
pub const MAX_LEVELS: usize = 16;

/// One analysis step of a `(h, w, c)` image: returns the `(ceil(h/2), ceil(w/2), c)` level.
fn analyse(img: &[f32], w: usize, h: usize, c: usize) -> (Vec<f32>, usize, usize) {
    let (cw, ch) = (w.div_ceil(2), h.div_ceil(2));
    let mut tmp = vec![0.0f32; h * cw * c];
    tmp.par_chunks_mut(cw * c).enumerate().for_each(|(y, row)| {
        let src = &img[y * w * c..(y + 1) * w * c];
        for i in 0..cw {
            for k in 0..c {
                let mut s = 0.0f32;
                for a in 0..4 {
                    let x = (2 * i + a) as i64 - 1;
                    if x >= 0 && (x as usize) < w {
                        s += src[x as usize * c + k];
                    }
                }
                row[i * c + k] = 0.25 * s;
            }
        }
    });
    let mut out = vec![0.0f32; ch * cw * c];
    out.par_chunks_mut(cw * c).enumerate().for_each(|(j, row)| {
        for b in 0..4 {
            let y = (2 * j + b) as i64 - 1;
            if y >= 0 && (y as usize) < h {
                let src = &tmp[y as usize * cw * c..(y as usize + 1) * cw * c];
                for (o, s) in row.iter_mut().zip(src) {
                    *o += s;
                }
            }
        }
        for o in row.iter_mut() {
            *o *= 0.25;
        }
    });
    (out, cw, ch)
}

/// Biquadratic B-spline expansion of a `(ch, cw, c)` level to `(h, w, c)`.
fn expand(coarse: &[f32], cw: usize, ch: usize, w: usize, h: usize, c: usize) -> Vec<f32> {
    let tap = |n: usize, x: usize| -> (usize, Option<usize>) {
        let i = x / 2;
        let j = if x % 2 == 0 {
            i.checked_sub(1)
        } else if i + 1 < n {
            Some(i + 1)
        } else {
            None
        };
        (i, j)
    };
    let mut tmp = vec![0.0f32; ch * w * c];
    tmp.par_chunks_mut(w * c).enumerate().for_each(|(y, row)| {
        let src = &coarse[y * cw * c..(y + 1) * cw * c];
        for x in 0..w {
            let (i, j) = tap(cw, x);
            for k in 0..c {
                let near = if i < cw { src[i * c + k] } else { 0.0 };
                let far = j.map_or(0.0, |j| src[j * c + k]);
                row[x * c + k] = 0.75 * near + 0.25 * far;
            }
        }
    });
    let mut out = vec![0.0f32; h * w * c];
    out.par_chunks_mut(w * c).enumerate().for_each(|(y, row)| {
        let (i, j) = tap(ch, y);
        let near = (i < ch).then(|| &tmp[i * w * c..(i + 1) * w * c]);
        let far = j.map(|j| &tmp[j * w * c..(j + 1) * w * c]);
        for (x, o) in row.iter_mut().enumerate() {
            let a = near.map_or(0.0, |r| r[x]);
            let b = far.map_or(0.0, |r| r[x]);
            *o = 0.75 * a + 0.25 * b;
        }
    });
    out
}

/// The analysis pyramid: level 0 is the input, level `l` has size `sizes[l]`.
struct Pyramid {
    levels: Vec<Vec<f32>>,
    sizes: Vec<(usize, usize)>,
}

fn build(img: &[f32], w: usize, h: usize, c: usize, levels: usize) -> Pyramid {
    let mut p = Pyramid {
        levels: vec![img.to_vec()],
        sizes: vec![(w, h)],
    };
    for l in 0..levels {
        let (lw, lh) = p.sizes[l];
        let (next, nw, nh) = analyse(&p.levels[l], lw, lh, c);
        p.levels.push(next);
        p.sizes.push((nw, nh));
    }
    p
}

/// Expands the top level of `p` down to level 0.
fn synth_blur(p: &Pyramid, c: usize) -> Vec<f32> {
    let top = p.levels.len() - 1;
    let mut cur = p.levels[top].clone();
    for l in (0..top).rev() {
        let (cw, ch) = p.sizes[l + 1];
        let (w, h) = p.sizes[l];
        cur = expand(&cur, cw, ch, w, h, c);
    }
    cur
}

/// Eqs. 8-9 on channel `k` of a `c`-channel pyramid; returns the level-0 glow `(h, w)`.
fn synth_glow(p: &Pyramid, c: usize, k: usize) -> Vec<f32> {
    let chan = |l: usize| -> Vec<f32> { p.levels[l].iter().skip(k).step_by(c).copied().collect() };
    let top = p.levels.len() - 1;
    let mut cur = chan(top);
    for l in (0..top).rev() {
        let (cw, ch) = p.sizes[l + 1];
        let (w, h) = p.sizes[l];
        let e = expand(&cur, cw, ch, w, h, 1);
        let a = chan(l);
        cur = e
            .par_iter()
            .zip(a.par_iter())
            .map(|(&e, &a)| e + a - e * a)
            .collect();
    }
    cur
}

fn check_levels(levels: usize) -> Result<()> {
    if levels > MAX_LEVELS {
        return Err(Error::value(
            "levels",
            format!("must be <= {MAX_LEVELS}, got {levels}"),
        ));
    }
    Ok(())
}

/// Pyramid blur of a `(h, w, 4)` image over `levels` levels (0 returns a copy).
pub fn pyramid_blur(rgba: &[f32], w: usize, h: usize, levels: usize) -> Result<Vec<f32>> {
    check_image("rgba", rgba, w, h, 4)?;
    check_levels(levels)?;
    check_finite("rgba", rgba)?;
    Ok(synth_blur(&build(rgba, w, h, 4, levels), 4))
}

/// Pyramid glow (eqs. 8-9) of a `(h, w)` alpha image over `levels` levels.
pub fn pyramid_glow(alpha: &[f32], w: usize, h: usize, levels: usize) -> Result<Vec<f32>> {
    check_image("alpha", alpha, w, h, 1)?;
    check_levels(levels)?;
    check_premultiplied("alpha", alpha, 1)?;
    Ok(synth_glow(&build(alpha, w, h, 1, levels), 1, 0))
}

/// Opaque pyramid blur of a `(h, w, 4)` image: pyramid blur and pyramid glow sharing one
/// analysis pyramid, then eq. 7 (`A_blur <= ALPHA_EPS` gives colour 0, alpha is the glow).
pub fn pyramid_opaque_blur(rgba: &[f32], w: usize, h: usize, levels: usize) -> Result<Vec<f32>> {
    check_image("rgba", rgba, w, h, 4)?;
    check_levels(levels)?;
    check_premultiplied("rgba", rgba, 4)?;
    Ok(opaque_unchecked(rgba, w, h, levels))
}

pub(crate) fn opaque_unchecked(rgba: &[f32], w: usize, h: usize, levels: usize) -> Vec<f32> {
    let p = build(rgba, w, h, 4, levels);
    let mut blur = synth_blur(&p, 4);
    let glow = synth_glow(&p, 4, 3);
    blur.par_chunks_mut(4)
        .zip(glow.par_iter())
        .for_each(|(px, &g)| {
            let s = if px[3] > ALPHA_EPS { g / px[3] } else { 0.0 };
            px[0] *= s;
            px[1] *= s;
            px[2] *= s;
            px[3] = g;
        });
    blur
}

/// Pyramid blur of a `(h, w, c)` image over `levels` levels, unchecked (0 returns a copy).
pub(crate) fn blur_unchecked(img: &[f32], w: usize, h: usize, c: usize, levels: usize) -> Vec<f32> {
    synth_blur(&build(img, w, h, c, levels), c)
}

/// Push-pull fill of a `(h, w, 4)` premultiplied image over `levels` levels, unchecked: the
/// glow's synthesis (eqs. 8-9) on every channel, `C_syn = C_ana + (1 - A_ana) C_exp`, so each
/// pixel keeps its colour and the transparent part of it is filled from the nearest coarser
/// level that has colour there (the pyramid interpolation of Kraus and Strengert 2007 that fills
/// disoccluded pixels). Alpha is the pyramid glow's.
pub(crate) fn push_pull_unchecked(rgba: &[f32], w: usize, h: usize, levels: usize) -> Vec<f32> {
    let p = build(rgba, w, h, 4, levels);
    let top = p.levels.len() - 1;
    let mut cur = p.levels[top].clone();
    for l in (0..top).rev() {
        let (cw, ch) = p.sizes[l + 1];
        let (w, h) = p.sizes[l];
        let mut e = expand(&cur, cw, ch, w, h, 4);
        e.par_chunks_mut(4)
            .zip(p.levels[l].par_chunks(4))
            .for_each(|(e, a)| {
                let k = 1.0 - a[3];
                for c in 0..4 {
                    e[c] = a[c] + k * e[c];
                }
            });
        cur = e;
    }
    cur
}

/// Levels that bring a `w` x `h` image down to one pixel (at most [`MAX_LEVELS`]).
pub(crate) fn levels_to_one(w: usize, h: usize) -> usize {
    let mut n = w.max(h);
    let mut l = 0;
    while n > 1 && l < MAX_LEVELS {
        n = n.div_ceil(2);
        l += 1;
    }
    l
}
