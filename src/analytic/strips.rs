//! The prims of a frame, set up strip by strip of tile rows: a frame whose prims would hold
//! more than twice the tile budget ([`Input::tile_budget`], 128 MiB by default; a turning mesh
//! of 100k faces over a hundred segments: 6M prims, 750 MB, and their bins) first finds which
//! tile rows each face-segment can reach (12 bytes each; a cheap bound, not the prim), then
//! sets up, bins and renders one strip at a time with only the prims that reach it. Each strip
//! sets up its prims in the frame's order (the whole frame's list, filtered: each group's
//! order along the motion is a stable sort, so sorting the strip's part gives the whole
//! list's order restricted to it), so every tile sees the same prims in the same order as in
//! one pass: the same bits.
use rayon::prelude::*;

use super::input::{Input, Prepared};
use super::prim::{self, Corners, Prim, OPAQUE};
use super::shade::TilePrim;
use super::tiles::tile_rows;

/// Faces set up per parallel job.
const CHUNK: usize = 2048;
/// Most bytes of prims (at most, before culling: faces x segments) set up for the whole frame
/// at once, and of one strip's prims and their shared set-up (`Prim` and `TilePrim` each), in
/// tile budgets.
const STRIP_BUDGETS: usize = 2;

/// The tile rows `[r0, r1)` face `face` of a (segment, draw) group can reach.
#[derive(Clone, Copy)]
struct Reach {
    face: u32,
    r0: i32,
    r1: i32,
}

/// How a frame's prims are set up: whole, or strip by strip.
pub(super) struct Plan {
    /// The strips of tile rows `[r0, r1)`, covering every row in order.
    pub strips: Vec<(i32, i32)>,
    /// The (segment, draw) groups, in frame order, and per group the rows its faces can reach
    /// (in face order): empty when the frame is set up whole.
    groups: Vec<(usize, usize)>,
    reach: Vec<Vec<Reach>>,
}

impl Plan {
    /// The plan of a frame of `ws` x `hs` samples, `ty` tile rows.
    pub fn new(input: &Input, prepared: &[Prepared], ws: u32, hs: u32, ty: i32) -> Plan {
        let segs = input.times.len() - 1;
        let most: usize = input.draws.iter().map(|d| d.faces.len() * segs).sum();
        let bytes = input.tile_budget.saturating_mul(STRIP_BUDGETS);
        if most.saturating_mul(std::mem::size_of::<Prim>()) <= bytes {
            return Plan {
                strips: vec![(0, ty)],
                groups: Vec::new(),
                reach: Vec::new(),
            };
        }
        let groups = groups(input);
        let reach: Vec<Vec<Reach>> = groups
            .par_iter()
            .map(|&(seg, di)| {
                let (d, p) = (&input.draws[di], &prepared[di]);
                let mut v = Vec::with_capacity(d.faces.len());
                for (fi, f) in d.faces.iter().enumerate() {
                    let c0 = f.map(|i| p.clip(seg * p.nv + i as usize));
                    let c1 = f.map(|i| p.clip((seg + 1) * p.nv + i as usize));
                    let c = Corners::new(c0, c1, f64::from(ws), f64::from(hs));
                    let (y0, y1) = prim::rows(&c, hs);
                    if y0 < y1 {
                        let (r0, r1) = tile_rows(y0, y1);
                        v.push(Reach {
                            face: fi as u32,
                            r0,
                            r1,
                        });
                    }
                }
                v
            })
            .collect();
        Plan {
            strips: strips(&reach, ty, bytes),
            groups,
            reach,
        }
    }

    /// The prims that reach tile rows `r0..r1`, in the frame's order (all of them when the
    /// frame is set up whole).
    pub fn prims_of(
        &self,
        input: &Input,
        prepared: &[Prepared],
        ws: u32,
        hs: u32,
        r0: i32,
        r1: i32,
    ) -> Vec<Prim> {
        if self.groups.is_empty() {
            return setup_prims(input, prepared, ws, hs);
        }
        let per: Vec<Vec<Prim>> = self
            .groups
            .par_iter()
            .zip(&self.reach)
            .map(|(&(seg, di), reach)| {
                let p = &prepared[di];
                let chunks: Vec<Vec<Prim>> = reach
                    .par_chunks(CHUNK)
                    .map(|c| {
                        c.iter()
                            .filter(|r| r.r0 < r1 && r.r1 > r0)
                            .filter_map(|r| face_prim(input, p, di, seg, r.face, ws, hs))
                            .filter(|q| {
                                let (b, d) = tile_rows(q.bbox[1], q.bbox[3]);
                                b < r1 && d > r0
                            })
                            .collect()
                    })
                    .collect();
                let mut group = concat(chunks);
                order_along_motion(&mut group, p, seg, ws, hs);
                group
            })
            .collect();
        concat(per)
    }

    /// Whether a strip of `prims` prims may set them up once for all its tiles: always the
    /// whole frame's rule (`fits`), and a strip's prims and their set-ups within its budget.
    pub fn shares(&self, input: &Input, prims: usize, fits: bool) -> bool {
        use std::mem::size_of;
        let bytes = input.tile_budget.saturating_mul(STRIP_BUDGETS);
        fits && (self.groups.is_empty()
            || prims.saturating_mul(size_of::<Prim>() + size_of::<TilePrim>()) <= bytes)
    }
}

/// The vectors of `parts` one after the other, each freed once copied (the peak is the
/// parts and one part more, not twice them).
fn concat(parts: Vec<Vec<Prim>>) -> Vec<Prim> {
    let mut out = Vec::with_capacity(parts.iter().map(Vec::len).sum());
    for p in parts {
        out.extend(p);
    }
    out
}

/// Strips of tile rows holding at most `bytes` of prims and shared set-up (one row at least).
fn strips(reach: &[Vec<Reach>], ty: i32, bytes: usize) -> Vec<(i32, i32)> {
    let rows = ty.max(0) as usize;
    // starts[r]: prims that start above row r; ends[r]: prims that end at or above it
    let (mut starts, mut ends) = (vec![0usize; rows + 1], vec![0usize; rows + 1]);
    for r in reach.iter().flatten() {
        let (a, b) = (r.r0.clamp(0, ty) as usize, r.r1.clamp(0, ty) as usize);
        if a < b {
            starts[a + 1] += 1;
            ends[b] += 1;
        }
    }
    for r in 0..rows {
        starts[r + 1] += starts[r];
        ends[r + 1] += ends[r];
    }
    let cap = bytes / std::mem::size_of::<Prim>();
    let mut out = Vec::new();
    let mut r0 = 0;
    while r0 < rows {
        // prims reaching rows r0..r1: started above r1 and not ended at or above r0
        let mut r1 = r0 + 1;
        while r1 < rows && starts[r1 + 1] - ends[r0] <= cap {
            r1 += 1;
        }
        out.push((r0 as i32, r1 as i32));
        r0 = r1;
    }
    if out.is_empty() {
        out.push((0, ty));
    }
    out
}

/// The (segment, draw) groups of a frame in its order.
fn groups(input: &Input) -> Vec<(usize, usize)> {
    (0..input.times.len() - 1)
        .flat_map(|seg| (0..input.draws.len()).map(move |di| (seg, di)))
        .collect()
}

/// Every face of every draw over every segment, in (segment, draw, face) order.
fn setup_prims(input: &Input, prepared: &[Prepared], ws: u32, hs: u32) -> Vec<Prim> {
    // (segment, draw) groups in parallel too: a deforming or turning mesh of a few hundred
    // faces cut into dozens of segments is one chunk per group
    let per_group: Vec<Vec<Prim>> = groups(input)
        .par_iter()
        .map(|&(seg, di)| group_prims(input, prepared, seg, di, ws, hs))
        .collect();
    concat(per_group)
}

/// The prims of one draw over one segment, in the frame's order.
fn group_prims(
    input: &Input,
    prepared: &[Prepared],
    seg: usize,
    di: usize,
    ws: u32,
    hs: u32,
) -> Vec<Prim> {
    let (d, p) = (&input.draws[di], &prepared[di]);
    let chunks: Vec<Vec<Prim>> = d
        .faces
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(ci, faces)| {
            (0..faces.len())
                .filter_map(|j| face_prim(input, p, di, seg, (ci * CHUNK + j) as u32, ws, hs))
                .collect()
        })
        .collect();
    let mut group = concat(chunks);
    order_along_motion(&mut group, p, seg, ws, hs);
    group
}

/// The prim of face `fi` of draw `di` over segment `seg`, or None where it is transparent,
/// culled or out of view.
fn face_prim(
    input: &Input,
    p: &Prepared,
    di: usize,
    seg: usize,
    fi: u32,
    ws: u32,
    hs: u32,
) -> Option<Prim> {
    let d = &input.draws[di];
    let f = d.faces[fi as usize];
    let alpha = f.map(|i| d.rgba[if d.rgba.len() == 1 { 0 } else { i as usize }][3]);
    if alpha.iter().all(|a| *a <= 0.0) {
        return None;
    }
    let c0 = f.map(|i| p.clip(seg * p.nv + i as usize));
    let c1 = f.map(|i| p.clip((seg + 1) * p.nv + i as usize));
    let corners = Corners::new(c0, c1, f64::from(ws), f64::from(hs));
    let (flags, front, back, bbox, hull, nhull) =
        prim::setup(&corners, &c0, &c1, d.cull_back, ws, hs)?;
    let opaque = p.opaque_everywhere || alpha.iter().all(|a| *a >= 1.0);
    Some(Prim {
        draw: di as u32,
        face: fi,
        seg: seg as u32,
        flags: flags | if opaque { OPAQUE } else { 0 },
        front,
        back,
        bbox,
        hull,
        nhull,
    })
}
/// Orders one draw's prims of one segment so that its leading side comes first: along the
/// draw's mean screen motion, a sample is reached by the triangles in this order, so the spans
/// of neighbouring triangles arrive one after the other and chain (a stable sort: ties keep
/// face order).
fn order_along_motion(group: &mut [Prim], p: &Prepared, seg: usize, ws: u32, hs: u32) {
    let (w, h) = (f64::from(ws), f64::from(hs));
    let step = (p.nv / 1024).max(1);
    let (mut dx, mut dy) = (0.0, 0.0);
    for v in (0..p.nv).step_by(step) {
        let (a, b) = (p.clip(seg * p.nv + v), p.clip((seg + 1) * p.nv + v));
        if a[3] > 0.0 && b[3] > 0.0 {
            let pa = prim::homogeneous_pixel(&a, w, h);
            let pb = prim::homogeneous_pixel(&b, w, h);
            dx += pb[0] / pb[2] - pa[0] / pa[2];
            dy += pb[1] / pb[2] - pa[1] / pa[2];
        }
    }
    if !(dx * dx + dy * dy > 0.0) {
        return;
    }
    let key = |q: &Prim| {
        let cx = f64::from(q.bbox[0] + q.bbox[2]);
        let cy = f64::from(q.bbox[1] + q.bbox[3]);
        -(cx * dx + cy * dy)
    };
    group.sort_by(|a, b| key(a).total_cmp(&key(b)));
}
