//! The two passes of one screen tile.
//!
//! Coverage (which samples a triangle covers, with the top-left rule) is `coverage.rs`.
//! Pass 1 (opaque) keeps the nearest opaque fragment of each sample in a visibility buffer
//! (1/w and the triangle's place in the bin), and shades only the winners. Pass 2 (transparent) collects
//! the transparent fragments in front of the opaque surface; `blend.rs` composites them (in
//! bounded lists, or each as it comes for `Blend::Unsorted`).
use super::background::Background;
use super::bins::TILE;
use super::blend::{Frag, FragLists, Sample};
use super::coverage::Edges;
use super::interp::Planes;
use super::options::Blend;
use super::setup::{Tri, MAY_OPAQUE, MAY_TRANSPARENT, ONE_SAMPLE};
use super::shade::{Shader, TriShade};
use std::time::Instant;

const NONE: u32 = u32::MAX;

/// What rendering a tile reports.
#[derive(Clone, Copy, Debug, Default)]
pub struct TileReport {
    /// Samples covered (both passes).
    pub fragments: u64,
    /// Whether the background held a bad value in the tile.
    pub bad_background: bool,
    /// Samples whose transparent fragments past `FRAGMENT_CAP` were merged approximately.
    pub approximated: u64,
    /// Bytes of an allocation the system refused (0: none; the frame then fails).
    pub refused: u64,
    /// Milliseconds: opaque coverage and depth test, opaque shading, the transparent pass
    /// (coverage, shading, compositing), resolve.
    pub ms: [f64; 4],
}

impl TileReport {
    /// The two reports' sums (`bad_background`: either).
    pub fn add(self, o: TileReport) -> TileReport {
        TileReport {
            fragments: self.fragments + o.fragments,
            bad_background: self.bad_background | o.bad_background,
            approximated: self.approximated + o.approximated,
            refused: self.refused.max(o.refused),
            ms: [0, 1, 2, 3].map(|k| self.ms[k] + o.ms[k]),
        }
    }
}

#[inline]
fn ms(a: Instant, b: Instant) -> f64 {
    (b - a).as_secs_f64() * 1e3
}

/// Calls `f(ix, iy)` for every sample of the (tile-clamped, non-empty) box `bx` that the
/// triangle covers, row by row, left to right.
#[inline(always)]
fn cover(t: &Tri, bx: [i32; 4], mut f: impl FnMut(i32, i32)) {
    if t.flags & ONE_SAMPLE != 0 {
        f(bx[0], bx[1]); // the set-up found the box's one sample covered
    } else {
        Edges::new(t.x, t.y).cover(bx, f);
    }
}

/// `Edges::spans` of the triangle in the (tile-clamped, non-empty) box `bx`.
#[inline(always)]
fn spans(t: &Tri, bx: [i32; 4], mut f: impl FnMut(i32, i32, i32)) {
    if t.flags & ONE_SAMPLE != 0 {
        f(bx[1], bx[0], bx[0]);
    } else {
        Edges::new(t.x, t.y).spans(bx, f);
    }
}

/// Reusable per-thread buffers of a tile.
pub struct TileScratch {
    pub zbuf: Vec<f32>,
    winner: Vec<u32>,
    pub samples: Vec<Sample>,
    frags: FragLists,
}

impl Default for TileScratch {
    fn default() -> Self {
        let n = (TILE * TILE) as usize;
        TileScratch {
            zbuf: vec![0.0; n],
            winner: vec![NONE; n],
            samples: vec![Sample::BACKGROUND; n],
            frags: FragLists::default(),
        }
    }
}

impl TileScratch {
    /// Releases fragment-list memory beyond what a thread keeps between tiles.
    pub fn trim(&mut self) {
        self.frags.trim();
    }
}

/// Renders the samples `rect` = [x0, y0, x1, y1) of a tile from its triangle references and
/// their triangles (`Bins::tile`, in submission order) into `scratch.samples` (row stride TILE), starting from `bg` when given
/// (else from the empty background). Returns the fragment count, and whether `bg` holds a bad
/// value in the rectangle (`Background::load`).
pub fn render_tile(
    rect: [i32; 4],
    refs: &[u32],
    tris: &[Tri],
    sh: &Shader,
    blend: Blend,
    bg: Option<&Background>,
    scratch: &mut TileScratch,
) -> TileReport {
    let [tx0, ty0, tx1, ty1] = rect;
    let clamp = |t: &Tri| {
        [
            t.bbox[0].max(tx0),
            t.bbox[1].max(ty0),
            t.bbox[2].min(tx1 - 1),
            t.bbox[3].min(ty1 - 1),
        ]
    };
    let local = |ix: i32, iy: i32| ((iy - ty0) * TILE + (ix - tx0)) as usize;
    let TileScratch {
        zbuf,
        winner,
        samples,
        frags,
    } = scratch;
    let bad_background = match bg {
        // Samples outside `rect` are never read back; the opaque pass only touches `rect`.
        Some(bg) => bg.load(rect, zbuf, samples),
        None => {
            zbuf.fill(0.0);
            false
        }
    };
    let t0 = Instant::now();
    let mut fragments = 0u64;
    let mut any_transparent = false;
    // Whether a triangle that may be opaque reaches the tile (`winner` is reset then only).
    let mut any_opaque = false;

    // Pass 1: opaque fragments, nearest wins (strictly nearer: the first submitted keeps ties).
    for (i, (&r, t)) in refs.iter().zip(tris).enumerate() {
        let i = i as u32;
        any_transparent |= t.flags & MAY_TRANSPARENT != 0;
        if t.flags & MAY_OPAQUE == 0 {
            continue;
        }
        let bx = clamp(t);
        if bx[0] > bx[2] || bx[1] > bx[3] {
            continue;
        }
        if !any_opaque {
            winner.fill(NONE);
            any_opaque = true;
        }
        // only a triangle that may also be transparent needs its alpha per sample
        let mixed = (t.flags & MAY_TRANSPARENT != 0).then(|| sh.prepare(r, t));
        let planes = Planes::new(t);
        cover(t, bx, |ix, iy| {
            fragments += 1;
            if let Some(ts) = &mixed {
                if ts.alpha(ts.lambdas(&planes, ix, iy)) < 1.0 {
                    return;
                }
            }
            let z = planes.invw(ix, iy) as f32;
            let s = local(ix, iy);
            if z > zbuf[s] {
                zbuf[s] = z;
                winner[s] = i;
            }
        });
    }

    let t1 = Instant::now();
    // Shade the opaque winners (neighbouring samples mostly share a triangle: keep its planes).
    // Without opaque triangles every sample keeps the background.
    if !any_opaque {
        if bg.is_none() {
            for iy in ty0..ty1 {
                let row = local(tx0, iy);
                samples[row..row + (tx1 - tx0) as usize].fill(Sample::BACKGROUND);
            }
        }
    } else {
        // (the planes only when the shading varies over the triangle)
        let mut cached = (NONE, None::<(Option<Planes>, TriShade)>);
        for iy in ty0..ty1 {
            for ix in tx0..tx1 {
                let s = local(ix, iy);
                let i = winner[s];
                if i == NONE && bg.is_some() {
                    continue; // the background sample loaded above stays
                }
                samples[s] = if i == NONE {
                    Sample::BACKGROUND
                } else {
                    if cached.0 != i {
                        let t = &tris[i as usize];
                        let ts = sh.prepare(refs[i as usize], t);
                        let planes = ts.constant().is_none().then(|| Planes::new(t));
                        cached = (i, Some((planes, ts)));
                    }
                    let (planes, ts) = cached.1.as_ref().expect("set above");
                    let sh = match (ts.constant(), planes) {
                        (Some(c), _) => c,
                        (None, p) => ts.shade_at(p.as_ref().expect("set above"), ix, iy),
                    };
                    Sample {
                        rgba: sh.rgba,
                        invw: zbuf[s],
                        id: sh.id,
                        velocity: sh.velocity,
                    }
                };
            }
        }
    }
    let t2 = Instant::now();
    let mut report = TileReport {
        fragments,
        bad_background,
        ms: [ms(t0, t1), ms(t1, t2), 0.0, 0.0],
        ..Default::default()
    };
    if !any_transparent {
        return report;
    }

    // Pass 2: transparent fragments in front of the opaque surface.
    frags.clear((TILE * TILE) as usize);
    for (&r, t) in refs.iter().zip(tris) {
        if t.flags & MAY_TRANSPARENT == 0 {
            continue;
        }
        let bx = clamp(t);
        if bx[0] > bx[2] || bx[1] > bx[3] {
            continue;
        }
        let planes = Planes::new(t);
        let mixed = t.flags & MAY_OPAQUE != 0;
        let ts = sh.prepare(r, t);
        if let Some(shaded) = ts.constant() {
            // A constant triangle has one alpha, so it is never mixed: one loop without the
            // shading's tests (the same fragments, in the same order).
            let keep = shaded.rgba[3] > 0.0;
            spans(t, bx, |iy, x0, x1| {
                for ix in x0..=x1 {
                    let s = local(ix, iy);
                    let z = planes.invw(ix, iy) as f32;
                    if z <= zbuf[s] {
                        continue;
                    }
                    fragments += 1;
                    if keep {
                        let f = Frag {
                            sample: s as u32,
                            invw: z,
                            shaded,
                        };
                        match blend {
                            Blend::Exact => frags.push(f),
                            Blend::Unsorted => frags.blend_unsorted(samples, f),
                        }
                    }
                }
            });
            continue;
        }
        spans(t, bx, |iy, x0, x1| {
            for ix in x0..=x1 {
                let s = local(ix, iy);
                let z = planes.invw(ix, iy) as f32;
                if z <= zbuf[s] {
                    continue;
                }
                let lam = ts.lambdas(&planes, ix, iy);
                if mixed && ts.alpha(lam) >= 1.0 {
                    continue;
                }
                let shaded = ts.shade(lam);
                fragments += 1;
                if shaded.rgba[3] > 0.0 {
                    let f = Frag {
                        sample: s as u32,
                        invw: z,
                        shaded,
                    };
                    match blend {
                        Blend::Exact => frags.push(f),
                        Blend::Unsorted => frags.blend_unsorted(samples, f),
                    }
                }
            }
        });
    }
    if blend == Blend::Exact {
        report.approximated = frags.composite(&mut samples[..(TILE * TILE) as usize]);
    }
    report.refused = frags.refused;
    report.fragments = fragments;
    report.ms[2] = ms(t2, Instant::now());
    report
}
