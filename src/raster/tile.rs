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

/// One tile's samples and its triangles, as the passes of `render_tile` read them.
struct Tile<'a> {
    /// The samples [x0, y0, x1, y1).
    rect: [i32; 4],
    /// The triangles' references and the triangles (`Bins::tile`, in submission order).
    refs: &'a [u32],
    tris: &'a [Tri],
    sh: &'a Shader<'a>,
}

impl Tile<'_> {
    /// The triangle's box clamped to the tile (empty when `x0 > x1` or `y0 > y1`).
    #[inline(always)]
    fn clamp(&self, t: &Tri) -> [i32; 4] {
        let [tx0, ty0, tx1, ty1] = self.rect;
        [
            t.bbox[0].max(tx0),
            t.bbox[1].max(ty0),
            t.bbox[2].min(tx1 - 1),
            t.bbox[3].min(ty1 - 1),
        ]
    }

    /// The index of sample (ix, iy) in the tile's buffers (row stride TILE).
    #[inline(always)]
    fn local(&self, ix: i32, iy: i32) -> usize {
        ((iy - self.rect[1]) * TILE + (ix - self.rect[0])) as usize
    }

    /// Pass 1: opaque fragments, nearest wins (strictly nearer: the first submitted keeps
    /// ties), into `zbuf` and `winner` (reset only when a triangle that may be opaque reaches
    /// the tile). Returns the fragments, whether a triangle may be transparent, and whether
    /// one may be opaque.
    fn opaque_pass(&self, zbuf: &mut [f32], winner: &mut [u32]) -> (u64, bool, bool) {
        let mut fragments = 0u64;
        let mut any_transparent = false;
        let mut any_opaque = false;
        for (i, (&r, t)) in self.refs.iter().zip(self.tris).enumerate() {
            let i = i as u32;
            any_transparent |= t.flags & MAY_TRANSPARENT != 0;
            if t.flags & MAY_OPAQUE == 0 {
                continue;
            }
            let bx = self.clamp(t);
            if bx[0] > bx[2] || bx[1] > bx[3] {
                continue;
            }
            if !any_opaque {
                winner.fill(NONE);
                any_opaque = true;
            }
            // only a triangle that may also be transparent needs its alpha per sample
            let mixed = (t.flags & MAY_TRANSPARENT != 0).then(|| self.sh.prepare(r, t));
            let planes = Planes::new(t);
            cover(t, bx, |ix, iy| {
                fragments += 1;
                if let Some(ts) = &mixed {
                    if ts.alpha(ts.lambdas(&planes, ix, iy)) < 1.0 {
                        return;
                    }
                }
                let z = planes.invw(ix, iy) as f32;
                let s = self.local(ix, iy);
                if z > zbuf[s] {
                    zbuf[s] = z;
                    winner[s] = i;
                }
            });
        }
        (fragments, any_transparent, any_opaque)
    }

    /// Shades the opaque winners into `samples` (neighbouring samples mostly share a
    /// triangle: its planes are kept, and made only when the shading varies over it). A
    /// sample without a winner keeps the background loaded when `has_bg`, else is empty.
    fn shade_winners(&self, zbuf: &[f32], winner: &[u32], samples: &mut [Sample], has_bg: bool) {
        let [tx0, ty0, tx1, ty1] = self.rect;
        let mut cached = (NONE, None::<(Option<Planes>, TriShade)>);
        for iy in ty0..ty1 {
            for ix in tx0..tx1 {
                let s = self.local(ix, iy);
                let i = winner[s];
                if i == NONE && has_bg {
                    continue; // the background sample loaded above stays
                }
                samples[s] = if i == NONE {
                    Sample::BACKGROUND
                } else {
                    if cached.0 != i {
                        let t = &self.tris[i as usize];
                        let ts = self.sh.prepare(self.refs[i as usize], t);
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

    /// Pass 2: the transparent fragments in front of the opaque surface (`zbuf`), into `frags`
    /// (`Blend::Exact`) or blended into `samples` as they come (`Blend::Unsorted`). Returns the
    /// fragments.
    fn transparent_pass(
        &self,
        zbuf: &[f32],
        samples: &mut [Sample],
        frags: &mut FragLists,
        blend: Blend,
    ) -> u64 {
        let mut fragments = 0u64;
        let mut keep = |f: Frag| match blend {
            Blend::Exact => frags.push(f),
            Blend::Unsorted => frags.blend_unsorted(samples, f),
        };
        for (&r, t) in self.refs.iter().zip(self.tris) {
            if t.flags & MAY_TRANSPARENT == 0 {
                continue;
            }
            let bx = self.clamp(t);
            if bx[0] > bx[2] || bx[1] > bx[3] {
                continue;
            }
            let planes = Planes::new(t);
            let mixed = t.flags & MAY_OPAQUE != 0;
            let ts = self.sh.prepare(r, t);
            if let Some(shaded) = ts.constant() {
                // A constant triangle has one alpha, so it is never mixed: one loop without the
                // shading's tests (the same fragments, in the same order).
                let visible = shaded.rgba[3] > 0.0;
                spans(t, bx, |iy, x0, x1| {
                    for ix in x0..=x1 {
                        let s = self.local(ix, iy);
                        let z = planes.invw(ix, iy) as f32;
                        if z <= zbuf[s] {
                            continue;
                        }
                        fragments += 1;
                        if visible {
                            keep(Frag {
                                sample: s as u32,
                                invw: z,
                                shaded,
                            });
                        }
                    }
                });
                continue;
            }
            spans(t, bx, |iy, x0, x1| {
                for ix in x0..=x1 {
                    let s = self.local(ix, iy);
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
                        keep(Frag {
                            sample: s as u32,
                            invw: z,
                            shaded,
                        });
                    }
                }
            });
        }
        fragments
    }
}

/// Renders the samples `rect` = [x0, y0, x1, y1) of a tile from its triangle references and
/// their triangles (`Bins::tile`, in submission order) into `scratch.samples` (row stride
/// TILE), starting from `bg` when given (else from the empty background). Returns the fragment
/// count, and whether `bg` holds a bad value in the rectangle (`Background::load`).
pub fn render_tile(
    rect: [i32; 4],
    refs: &[u32],
    tris: &[Tri],
    sh: &Shader,
    blend: Blend,
    bg: Option<&Background>,
    scratch: &mut TileScratch,
) -> TileReport {
    let tile = Tile {
        rect,
        refs,
        tris,
        sh,
    };
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
    let (mut fragments, any_transparent, any_opaque) = tile.opaque_pass(zbuf, winner);
    let t1 = Instant::now();
    if any_opaque {
        tile.shade_winners(zbuf, winner, samples, bg.is_some());
    } else if bg.is_none() {
        // Without opaque triangles every sample keeps the background.
        let [tx0, ty0, tx1, ty1] = rect;
        for iy in ty0..ty1 {
            let row = tile.local(tx0, iy);
            samples[row..row + (tx1 - tx0) as usize].fill(Sample::BACKGROUND);
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
    frags.clear((TILE * TILE) as usize);
    fragments += tile.transparent_pass(zbuf, samples, frags, blend);
    if blend == Blend::Exact {
        report.approximated = frags.composite(&mut samples[..(TILE * TILE) as usize]);
    }
    report.refused = frags.refused;
    report.fragments = fragments;
    report.ms[2] = ms(t2, Instant::now());
    report
}
