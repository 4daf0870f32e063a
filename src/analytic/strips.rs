//! The prims of a frame, set up strip by strip of tile rows: a frame whose prims would hold
//! more than twice the tile budget ([`Input::tile_budget`], 128 MiB by default; a turning mesh
//! of 100k faces over a hundred segments: 6M prims, 750 MB, and their bins) first finds which
//! tile rows each face-segment can reach (a cheap bound, not the prim: 4 bytes each, then 2 as
//! a range of strips), then sets up, bins and renders one strip at a time with only the prims
//! that reach it and only the clip positions those use ([`Plan::tables`]; the frame's would be
//! 32 bytes per vertex and boundary). Each strip sets up its prims in the frame's order (the
//! whole frame's list, filtered: each group's order along the motion is a stable sort, so
//! sorting the strip's part gives the whole list's order restricted to it), so every tile sees
//! the same prims in the same order as in one pass: the same bits.
use rayon::prelude::*;

use super::clip::{ClipTable, Marks};
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

/// Faces of the (segment, draw) groups a strip sets up at once: their prims in the strip are
/// held twice while they join the strip's list (at most 32 MB of them).
const BATCH_FACES: usize = 1 << 18;

/// Where each face of each (segment, draw) group reaches, group after group, each in face
/// order (one vector: a few large ones are given back to the system when freed, where many
/// smaller ones would stay in the allocator's heap): first as tile rows, then (at most 256
/// strips) as strips.
enum Reach {
    /// The tile rows `[r0, r1)` (empty: `[0, 0)`); rows fit: an image has at most 32768 / 32.
    Rows(Vec<[u16; 2]>),
    /// The strips `s0..=s1` (none: `[1, 0]`).
    Strips(Vec<[u8; 2]>),
}

/// How a frame's prims are set up: whole, or strip by strip.
pub(super) struct Plan {
    /// The strips of tile rows `[r0, r1)`, covering every row in order.
    pub strips: Vec<(i32, i32)>,
    /// Per strip, the face-segments that reach it (its most prims).
    most: Vec<usize>,
    /// The (segment, draw) groups, in frame order, and where their faces reach (group `g`'s
    /// from `first[g]` to `first[g + 1]`): empty when the frame is set up whole.
    groups: Vec<(usize, usize)>,
    first: Vec<usize>,
    reach: Reach,
}

/// Whether a frame's prims are set up at once (within twice the tile budget at most), not strip
/// by strip.
pub(super) fn whole(input: &Input) -> bool {
    let segs = input.times.len() - 1;
    let most: usize = input.draws.iter().map(|d| d.faces.len() * segs).sum();
    let bytes = input.tile_budget.saturating_mul(STRIP_BUDGETS);
    most.saturating_mul(std::mem::size_of::<Prim>()) <= bytes
}

impl Plan {
    /// The plan of a frame of `ws` x `hs` samples, `ty` tile rows.
    pub fn new(input: &Input, prepared: &[Prepared], ws: u32, hs: u32, ty: i32) -> Plan {
        if whole(input) {
            return Plan {
                strips: vec![(0, ty)],
                most: Vec::new(),
                groups: Vec::new(),
                first: Vec::new(),
                reach: Reach::Rows(Vec::new()),
            };
        }
        let bytes = input.tile_budget.saturating_mul(STRIP_BUDGETS);
        let groups = groups(input);
        let mut first = vec![0];
        for &(_, di) in &groups {
            first.push(first[first.len() - 1] + input.draws[di].faces.len());
        }
        let mut rows = vec![[0u16; 2]; first[groups.len()]];
        let mut parts = Vec::with_capacity(groups.len());
        let mut rest = &mut rows[..];
        for w in first.windows(2) {
            let (part, later) = rest.split_at_mut(w[1] - w[0]);
            parts.push(part);
            rest = later;
        }
        // each job computes its group's two boundaries' clip positions once into `ends`
        parts
            .into_par_iter()
            .zip(&groups)
            .for_each_init(Vec::new, |ends, (part, &(seg, di))| {
                let (d, p) = (&input.draws[di], &prepared[di]);
                ends.clear();
                ends.extend((0..p.nv).map(|v| p.clip_at(seg, v)));
                ends.extend((0..p.nv).map(|v| p.clip_at(seg + 1, v)));
                for (r, f) in part.iter_mut().zip(d.faces) {
                    let c0 = f.map(|i| ends[i as usize]);
                    let c1 = f.map(|i| ends[p.nv + i as usize]);
                    let c = Corners::new(c0, c1, f64::from(ws), f64::from(hs));
                    let (y0, y1) = prim::rows(&c, hs);
                    if y0 < y1 {
                        let (r0, r1) = tile_rows(y0, y1);
                        *r = [r0 as u16, r1 as u16];
                    }
                }
            });
        let (strips, most) = strips(&rows, ty, bytes);
        Plan {
            reach: as_strips(rows, &strips, ty),
            strips,
            most,
            groups,
            first,
        }
    }

    /// The prims that reach strip `si`, in the frame's order (all of them when the frame is
    /// set up whole).
    pub fn prims_of(
        &self,
        input: &Input,
        prepared: &[Prepared],
        ws: u32,
        hs: u32,
        si: usize,
    ) -> Vec<Prim> {
        if self.groups.is_empty() {
            return setup_prims(input, prepared, ws, hs);
        }
        let (r0, r1) = self.strips[si];
        let faces = |g: usize| input.draws[self.groups[g].1].faces.len();
        // reserved for every face-segment that reaches the strip: the pages of those culled
        // are never touched
        let mut out = Vec::with_capacity(self.most[si]);
        let mut g = 0;
        while g < self.groups.len() {
            let (mut e, mut n) = (g + 1, faces(g));
            while e < self.groups.len() && n + faces(e) <= BATCH_FACES {
                n += faces(e);
                e += 1;
            }
            let batch: Vec<Vec<Prim>> = (g..e)
                .into_par_iter()
                .map(|gi| {
                    let (seg, di) = self.groups[gi];
                    let p = &prepared[di];
                    let make = |fi: u32| {
                        face_prim(input, p, di, seg, fi, ws, hs).filter(|q| {
                            let (b, d) = tile_rows(q.bbox[1], q.bbox[3]);
                            b < r1 && d > r0
                        })
                    };
                    let faces = self.first[gi]..self.first[gi + 1];
                    let chunks = match &self.reach {
                        Reach::Rows(r) => chunked(&r[faces], make, |r| {
                            i32::from(r[0]) < r1 && i32::from(r[1]) > r0
                        }),
                        Reach::Strips(s) => chunked(&s[faces], make, |s| {
                            usize::from(s[0]) <= si && si <= usize::from(s[1])
                        }),
                    };
                    let mut group = concat(chunks);
                    order_along_motion(&mut group, p, seg, ws, hs);
                    group
                })
                .collect();
            for v in batch {
                out.extend(v);
            }
            g = e;
        }
        out
    }

    /// The clip positions `prims` (a strip's) read, per draw: their corners' at their
    /// segment's ends and (for velocity) at the first and last boundary. Empty when the frame
    /// is set up whole: its draws hold every point's.
    pub fn tables(&self, input: &Input, prepared: &[Prepared], prims: &[Prim]) -> Vec<ClipTable> {
        if self.groups.is_empty() {
            return Vec::new();
        }
        let last = input.times.len() - 1;
        let marks: Vec<Marks> = prepared
            .iter()
            .map(|p| Marks::new((last + 1) * p.nv))
            .collect();
        prims.par_iter().with_min_len(1024).for_each(|q| {
            let (m, nv) = (&marks[q.draw as usize], prepared[q.draw as usize].nv);
            let seg = q.seg as usize;
            for v in input.draws[q.draw as usize].faces[q.face as usize] {
                for k in [seg, seg + 1, 0, last] {
                    m.mark(k * nv + v as usize);
                }
            }
        });
        prepared
            .iter()
            .zip(marks)
            .map(|(p, m)| p.table(m))
            .collect()
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

/// The prims of one group's faces `reach` (in face order) accepts, `make` of each face, in
/// parallel chunks.
fn chunked<R: Sync>(
    reach: &[R],
    make: impl Fn(u32) -> Option<Prim> + Sync,
    accepts: impl Fn(&R) -> bool + Sync,
) -> Vec<Vec<Prim>> {
    reach
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(ci, c)| {
            (c.iter().enumerate())
                .filter(|(_, r)| accepts(r))
                .filter_map(|(j, _)| make((ci * CHUNK + j) as u32))
                .collect()
        })
        .collect()
}

/// Strips of tile rows holding at most `bytes` of prims and shared set-up (one row at least),
/// and the face-segments that reach each.
fn strips(reach: &[[u16; 2]], ty: i32, bytes: usize) -> (Vec<(i32, i32)>, Vec<usize>) {
    let rows = ty.max(0) as usize;
    // starts[r]: prims that start above row r; ends[r]: prims that end at or above it
    let (mut starts, mut ends) = (vec![0usize; rows + 1], vec![0usize; rows + 1]);
    for r in reach {
        let (a, b) = (
            i32::from(r[0]).clamp(0, ty) as usize,
            i32::from(r[1]).clamp(0, ty) as usize,
        );
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
    let (mut out, mut most) = (Vec::new(), Vec::new());
    let mut r0 = 0;
    while r0 < rows {
        // prims reaching rows r0..r1: started above r1 and not ended at or above r0
        let mut r1 = r0 + 1;
        while r1 < rows && starts[r1 + 1] - ends[r0] <= cap {
            r1 += 1;
        }
        out.push((r0 as i32, r1 as i32));
        most.push(starts[r1] - ends[r0]);
        r0 = r1;
    }
    if out.is_empty() {
        out.push((0, ty));
        most.push(0);
    }
    (out, most)
}

/// The reach of `rows` as strips when there are at most 256, else as rows: a quarter of the
/// bytes (a turning mesh of 100k faces over a hundred segments: 25 MB).
fn as_strips(rows: Vec<[u16; 2]>, strips: &[(i32, i32)], ty: i32) -> Reach {
    if strips.len() > 256 {
        return Reach::Rows(rows);
    }
    let mut strip_of = vec![0u8; ty.max(0) as usize];
    for (si, &(a, b)) in strips.iter().enumerate() {
        strip_of[a as usize..b as usize].fill(si as u8);
    }
    let to = |r: &[u16; 2]| {
        let (a, b) = (usize::from(r[0]), usize::from(r[1]).min(strip_of.len()));
        if a < b {
            [strip_of[a], strip_of[b - 1]]
        } else {
            [1, 0]
        }
    };
    Reach::Strips(rows.par_iter().with_min_len(4096).map(to).collect())
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
    let c0 = f.map(|i| p.clip_at(seg, i as usize));
    let c1 = f.map(|i| p.clip_at(seg + 1, i as usize));
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
        let (a, b) = (p.clip_at(seg, v), p.clip_at(seg + 1, v));
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
