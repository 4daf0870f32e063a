//! Blur shells for deforming meshes (Jones and Keyser, "Real-Time Geometric Motion Blur for a
//! Deforming Polygonal Mesh"): the silhouette of motion, per-polygon history rings, hysteresis
//! and fading.
//!
//! A [`BlurShell`] is fed the mesh's world positions at each *update* and builds, on demand, a
//! shell of quad strips attached to the current mesh. The rules (the paper leaves some open;
//! each choice is stated here, in the Python docstring, and tested):
//!
//! - **Silhouette of motion** ([`silhouette`]): a moving vertex is front when
//!   `n . (p - p_prev) >= 0` and back when `< 0`; a triangle with one front and two back corners
//!   has the edge between its back corners on the silhouette. A vertex that does not move is
//!   neutral (neither), so a static polygon never has an edge. The first update has no previous
//!   positions, so it finds no silhouette.
//! - **History ring.** Each polygon keeps a ring of `subdivisions` elements, one per update,
//!   each an edge code (the local edge `k`, and whether it was on the silhouette then).
//!   Positions are not copied per polygon: the shell keeps the last `subdivisions` snapshots of
//!   all vertex positions and raw normals (`f32`: the given normals, or the area-weighted ones
//!   the facing test computed), and an element's pair is its edge's vertices in the snapshot
//!   of its update. The facing test runs on these float32 positions. A polygon off the silhouette
//!   records the last edge it had (the paper's "positions of the last blurred vertices").
//! - **Performance.** Four parallel passes per update over fixed chunks (results independent
//!   of the thread count): scatter the positions to a breadth-first vertex order
//!   ([`silhouette::Locality`]), face normals, vertex normals and facing, then the per-polygon
//!   step, which reads one fade byte per polygon and touches nothing else for polygons without
//!   a strip or an edge. No allocation per update. Meshes under [`PAR_MIN_FACES`] faces run
//!   the same chunks in order on the calling thread.
//! - **Birth.** A polygon whose strip is dead (or that never had one) and gains an edge at
//!   update `n` starts a strip with two elements: its edge at update `n` and the same edge at
//!   update `n - 1`, where the motion that put it on the silhouette started. So a shell fed
//!   `subdivisions + 1` positions spans all of them.
//! - **Fade level** `d` per polygon (0 = full strength): off the silhouette for more than
//!   `hysteresis` updates it rises by one per update; on the silhouette it falls by one per
//!   update (so a strip that comes back fades back in rather than popping). The strip is dead
//!   at `d == subdivisions`; a dead polygon records nothing.
//! - **Alpha.** Pair `j` of a strip (`j = 0` the base on the current mesh, `j = i + 1` the ring
//!   element recorded `i` updates ago) has alpha `initial_alpha * (1 - max(j, d) / subdivisions)`
//!   (`f32`). With `d = 0` this is the paper's ramp: `initial_alpha / subdivisions` less per
//!   pair, 0 at the last of `subdivisions + 1` pairs. Every strip vertex that exists in two
//!   consecutive builds (the base of one build is element 0 of the next) changes alpha by at
//!   most `initial_alpha / subdivisions`, and a vertex disappears only at alpha <= that step.
//! - **Attachment.** The base pair is the polygon's last silhouette edge at the current
//!   positions: exactly the positions given to `build`, or else the float32 snapshot of the
//!   last update.
use rayon::prelude::*;

use crate::mesh::MAX_ELEMENTS;
use crate::{Error, Result};

mod build;
pub mod silhouette;
#[cfg(test)]
mod tests;

pub use build::{BuildPlan, ShellMesh, ShellOut};
use silhouette::{face_edge, face_normals_into, facing, Locality, CHUNK, NEUTRAL, NO_EDGE};
pub use silhouette::{motion_silhouette, BACK, FRONT};

/// Edge-code bit: the element's edge was on the silhouette at its update.
pub const ON_SILHOUETTE: u8 = 4;
/// Largest `subdivisions` (the fade level is a `u8`).
pub const MAX_SUBDIVISIONS: u32 = 255;
/// Largest memory a shell may take for its history (snapshots, rings, tables), in bytes.
pub const MAX_HISTORY_BYTES: u64 = 8_000_000_000;
/// Largest `hysteresis` (the count of updates off the silhouette is a saturating `u16`).
pub const MAX_HYSTERESIS: u32 = 65_000;

/// A raw pointer shared by the scatter of pass A; each row writes its own slot.
struct SharedSlots<T>(*mut T);
unsafe impl<T: Send> Sync for SharedSlots<T> {}
unsafe impl<T: Send> Send for SharedSlots<T> {}

/// Shell options (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShellOptions {
    pub subdivisions: u32,
    pub hysteresis: u32,
    pub initial_alpha: f32,
}

impl Default for ShellOptions {
    fn default() -> Self {
        ShellOptions {
            subdivisions: 10,
            hysteresis: 3,
            initial_alpha: 1.0,
        }
    }
}

/// The shell's colour: one RGB for every strip, or the RGB of each mesh vertex.
#[derive(Debug, Clone, PartialEq)]
pub enum ShellColor {
    Uniform([f32; 3]),
    PerVertex(Vec<[f32; 3]>),
}

/// Per-polygon state as reported by [`BlurShell::state`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FaceState {
    /// Local index of the last silhouette edge, or `NO_EDGE`.
    pub last: u8,
    /// Fade level `d`; the strip is dead at `d >= subdivisions`.
    pub fade: u8,
    /// Number of valid ring elements (newest first), at most `subdivisions`.
    pub run: u8,
    /// Updates since the polygon last had a silhouette edge (saturating).
    pub since: u16,
}

/// The rest of a polygon's state, touched only when it has or gains a strip. The fade levels
/// live in their own byte array, so the update pass reads one byte per polygon and writes
/// nothing for the (many) polygons without a strip and without an edge.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Hot {
    last: u8,
    run: u8,
    /// Update index of the last silhouette edge (`NEVER`: none); `since` is derived from it.
    last_on: u32,
}

const NEVER: u32 = u32::MAX;

impl Hot {
    const INITIAL: Hot = Hot {
        last: NO_EDGE,
        run: 0,
        last_on: NEVER,
    };
}

/// The stateful blur shell of one mesh (fixed faces and vertex count).
#[derive(Debug)]
pub struct BlurShell {
    faces: Vec<[u32; 3]>,
    n_vertices: usize,
    opts: ShellOptions,
    mask: Option<Vec<bool>>,
    color: ShellColor,
    /// Internal vertex and face order of the per-update passes (see [`Locality`]).
    loc: Locality,
    updates: u64,
    facing: Vec<i8>,
    face_n: Vec<[f32; 3]>,
    /// `subdivisions + 1` buffers of float32 positions: one per ring slot (`buf_of_slot`) and
    /// a spare that the next update fills, so a failed update leaves every snapshot intact.
    pos_bufs: Vec<Vec<[f32; 3]>>,
    /// Raw float32 vertex normals per buffer: the given ones, or the unnormalised area-weighted
    /// ones the update computed for the facing test (stored as it goes, so build() reads them
    /// instead of recomputing face normals around every strip vertex).
    nrm_bufs: Vec<Vec<[f32; 3]>>,
    buf_of_slot: Vec<usize>,
    spare: usize,
    /// Edge codes, slot-major (`slot * F + f`).
    ring: Vec<u8>,
    /// With one subdivision the birth element shares the ring row; it goes here instead.
    scratch_row: Vec<u8>,
    fade: Vec<u8>,
    hot: Vec<Hot>,
}

/// Meshes with fewer faces run updates and builds sequentially (see [`BlurShell::parallel`]).
pub const PAR_MIN_FACES: usize = 4 * CHUNK;

/// Largest accepted |coordinate| of positions (scene units). Everything runs in float32: a face
/// normal is a product of two coordinate differences (up to `8 MAX_COORD^2` per component),
/// a vertex sums at most 2^32 of them and `n . d` multiplies by another difference, which stays
/// below `f32::MAX` (3.4e38) at this bound; float32 positions near it are 64 units apart anyway.
pub const MAX_COORD: f64 = 1e9;
/// Largest accepted |component| of given normals (`3 MAX_NORMAL 2 MAX_COORD` fits in float32).
pub const MAX_NORMAL: f64 = 1e18;

/// The bound of the rows called `name`: `MAX_NORMAL` for normals, else `MAX_COORD`.
pub(crate) fn limit_of(name: &str) -> f64 {
    if name == "normals" {
        MAX_NORMAL
    } else {
        MAX_COORD
    }
}

/// Fails naming `name` at the first row with a NaN, an inf or a value beyond `limit_of(name)`.
pub(crate) fn check_values(a: &[[f64; 3]], name: &'static str) -> Result<()> {
    let lim = limit_of(name);
    if let Some(bad) = a
        .par_iter()
        .position_first(|v| v.iter().any(|x| x.is_nan() || x.abs() > lim))
    {
        let row = a[bad];
        if row.iter().all(|x| x.is_finite()) {
            return Err(Error::value(
                name,
                format!(
                    "row {bad} has a value beyond +-{lim:e} ({row:?}): float32 normals or \
                     dot products would overflow"
                ),
            ));
        }
        return Err(Error::value(name, format!("row {bad} is NaN or inf")));
    }
    Ok(())
}

fn check_rows(a: &[[f64; 3]], n: usize, name: &'static str) -> Result<()> {
    if a.len() != n {
        return Err(Error::shape(
            name,
            format!(
                "expected {n} rows (the shell's vertex count), got {}; a BlurShell keeps its \
                 vertex count: make a new shell for a mesh with other vertices",
                a.len()
            ),
        ));
    }
    check_values(a, name)
}

impl BlurShell {
    /// A shell for `faces` over `n_vertices` vertices. Errors name `faces`, `subdivisions`,
    /// `hysteresis`, `initial_alpha`, `mask` or `color`.
    pub fn new(
        faces: Vec<[u32; 3]>,
        n_vertices: usize,
        opts: ShellOptions,
        mask: Option<Vec<bool>>,
        color: ShellColor,
    ) -> Result<Self> {
        if faces.is_empty() {
            return Err(Error::shape("faces", "is empty"));
        }
        if faces.len() > MAX_ELEMENTS || n_vertices > MAX_ELEMENTS {
            return Err(Error::shape("faces", "too many faces or vertices"));
        }
        if n_vertices == 0 {
            return Err(Error::shape("vertices", "is empty"));
        }
        let nv = n_vertices as u32;
        if let Some(bad) = faces
            .par_iter()
            .position_first(|f| f.iter().any(|&i| i >= nv))
        {
            return Err(Error::value(
                "faces",
                format!("face {bad} has an index out of range [0, {nv})"),
            ));
        }
        if !(1..=MAX_SUBDIVISIONS).contains(&opts.subdivisions) {
            return Err(Error::value(
                "subdivisions",
                format!(
                    "must be in 1..={MAX_SUBDIVISIONS}, got {}",
                    opts.subdivisions
                ),
            ));
        }
        if opts.hysteresis > MAX_HYSTERESIS {
            return Err(Error::value(
                "hysteresis",
                format!("must be in 0..={MAX_HYSTERESIS}, got {}", opts.hysteresis),
            ));
        }
        if !(opts.initial_alpha > 0.0 && opts.initial_alpha <= 1.0) {
            return Err(Error::value(
                "initial_alpha",
                format!("must be in (0, 1], got {}", opts.initial_alpha),
            ));
        }
        if let Some(m) = &mask {
            if m.len() != faces.len() {
                return Err(Error::shape(
                    "mask",
                    format!(
                        "expected {} values (one per face), got {}",
                        faces.len(),
                        m.len()
                    ),
                ));
            }
        }
        let bad_rgb = |c: &[f32; 3]| c.iter().any(|x| !x.is_finite() || *x < 0.0);
        match &color {
            ShellColor::Uniform(c) if bad_rgb(c) => {
                return Err(Error::value("color", "must be finite and >= 0"));
            }
            ShellColor::PerVertex(v) if v.len() != n_vertices => {
                return Err(Error::shape(
                    "color",
                    format!("expected (3,) or ({n_vertices},3), got {} rows", v.len()),
                ));
            }
            ShellColor::PerVertex(v) if v.iter().any(bad_rgb) => {
                return Err(Error::value("color", "must be finite and >= 0"));
            }
            _ => {}
        }
        let s = opts.subdivisions as usize;
        let nf = faces.len();
        // Positions and normals (12 bytes each per vertex and buffer), ring, per-face state.
        let bytes =
            (s as u128 + 1) * n_vertices as u128 * 24 + s as u128 * nf as u128 + 64 * nf as u128;
        if bytes > MAX_HISTORY_BYTES as u128 {
            return Err(Error::value(
                "subdivisions",
                format!(
                    "{} subdivisions over {n_vertices} vertices and {nf} faces need {:.1} GB of \
                     history (limit {} GB); use fewer subdivisions or a smaller mesh",
                    opts.subdivisions,
                    bytes as f64 / 1e9,
                    MAX_HISTORY_BYTES / 1_000_000_000
                ),
            ));
        }
        let loc = Locality::new(&faces, n_vertices);
        Ok(BlurShell {
            loc,
            n_vertices,
            opts,
            mask,
            color,
            updates: 0,
            facing: vec![NEUTRAL; n_vertices],
            face_n: vec![[0.0; 3]; nf],
            pos_bufs: vec![vec![[0.0; 3]; n_vertices]; s + 1],
            nrm_bufs: vec![vec![[0.0; 3]; n_vertices]; s + 1],
            buf_of_slot: (0..s).collect(),
            spare: s,
            ring: vec![NO_EDGE; s * nf],
            scratch_row: if s == 1 {
                vec![NO_EDGE; nf]
            } else {
                Vec::new()
            },
            fade: vec![u8::MAX; nf],
            hot: vec![Hot::INITIAL; nf],
            faces,
        })
    }

    /// Raw float32 normal of internal vertex `iv` in buffer `buf`: the given one, or the sum of
    /// the face normals around it that the update of that buffer computed.
    #[inline]
    fn raw_normal(&self, buf: usize, iv: usize) -> [f32; 3] {
        self.nrm_bufs[buf][iv]
    }

    /// Whether updates and builds run their chunks on rayon's pool: only for meshes of at
    /// least [`PAR_MIN_FACES`] faces. Smaller ones run the same chunks in order on the calling
    /// thread (fork/join and hand-overs cost more than the work), with the same results.
    pub fn parallel(&self) -> bool {
        self.faces.len() >= PAR_MIN_FACES
    }

    pub fn options(&self) -> ShellOptions {
        self.opts
    }
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }
    pub fn n_vertices(&self) -> usize {
        self.n_vertices
    }
    /// Number of updates since construction or the last reset.
    pub fn updates(&self) -> u64 {
        self.updates
    }
    /// Per-polygon state (`since` saturates at 65535; update counts wrap after 2^32 updates).
    pub fn state(&self) -> Vec<FaceState> {
        let n = self.updates.wrapping_sub(1) as u32;
        self.fade
            .iter()
            .zip(&self.hot)
            .map(|(&fade, h)| FaceState {
                last: h.last,
                fade,
                run: h.run,
                since: if h.last_on == NEVER {
                    u16::MAX
                } else {
                    n.wrapping_sub(h.last_on).min(u16::MAX as u32) as u16
                },
            })
            .collect()
    }
    /// Vertex facing of the last update (`FRONT`, `BACK`, `NEUTRAL`), in the caller's order.
    pub fn facing(&self) -> Vec<i8> {
        let mut out = vec![NEUTRAL; self.n_vertices];
        for (i, &p) in self.loc.perm.iter().enumerate() {
            out[p as usize] = self.facing[i];
        }
        out
    }
    /// The update index (ring slot) of the most recent element, as the paper's global index.
    pub fn update_index(&self) -> Option<usize> {
        self.updates
            .checked_sub(1)
            .map(|m| (m % self.opts.subdivisions as u64) as usize)
    }
    /// The ring element of face `f` recorded `i` updates ago (`i < run`): edge code, with
    /// `ON_SILHOUETTE` set when it was on the silhouette.
    pub fn element(&self, f: usize, i: usize) -> Option<u8> {
        let st = self.hot.get(f)?;
        if self.fade[f] as u32 >= self.opts.subdivisions || i >= st.run as usize {
            return None;
        }
        let s = self.opts.subdivisions as u64;
        let slot = ((self.updates - 1 - i as u64) % s) as usize;
        Some(self.ring[slot * self.faces.len() + f])
    }

    /// Forget every update: no strips, and the next update finds no silhouette.
    pub fn reset(&mut self) {
        self.updates = 0;
        self.fade.fill(u8::MAX);
        self.hot.fill(Hot::INITIAL);
        self.facing.fill(NEUTRAL);
    }

    /// Feed the mesh's world positions (V,3) and optionally its normals (V,3) at one update.
    /// Errors name `vertices` or `normals` (wrong count, NaN or inf, beyond `MAX_COORD` /
    /// `MAX_NORMAL`); the state is then unchanged.
    pub fn update(&mut self, vertices: &[[f64; 3]], normals: Option<&[[f64; 3]]>) -> Result<()> {
        if vertices.len() != self.n_vertices {
            return check_rows(vertices, self.n_vertices, "vertices");
        }
        if let Some(nr) = normals {
            if nr.len() != self.n_vertices {
                return check_rows(nr, self.n_vertices, "normals");
            }
        }
        let s = self.opts.subdivisions as usize;
        let nf = self.faces.len();
        let n = self.updates;
        let slot = (n % s as u64) as usize;
        // Pass A: float32 positions (and given normals) into the spare buffers, checking
        // finiteness on the way. The caller's rows are read in order and scattered to their
        // internal slots (stores do not stall on cache misses as gathered loads do).
        let spare = self.spare;
        let par = self.parallel();
        if scatter_f32(
            vertices,
            &self.loc.inv,
            &mut self.pos_bufs[spare],
            MAX_COORD,
            par,
        ) {
            return check_rows(vertices, self.n_vertices, "vertices");
        }
        if let Some(nr) = normals {
            if scatter_f32(
                nr,
                &self.loc.inv,
                &mut self.nrm_bufs[spare],
                MAX_NORMAL,
                par,
            ) {
                return check_rows(nr, self.n_vertices, "normals");
            }
        }
        let cur = &self.pos_bufs[spare];
        // Pass B: face normals (unless given).
        if normals.is_none() {
            if par {
                face_normals_into(cur, &self.loc.bfaces, &mut self.face_n);
            } else {
                for (o, f) in self.face_n.iter_mut().zip(&self.loc.bfaces) {
                    *o = crate::mesh::face_normal(cur, f);
                }
            }
        }
        // Pass C: vertex normals and facing against the previous update's positions.
        {
            let prev =
                (n > 0).then(|| &self.pos_bufs[self.buf_of_slot[((n - 1) % s as u64) as usize]]);
            let (face_n, vf) = (&self.face_n, &self.loc.vf);
            let given = normals.is_some();
            let nb = &mut self.nrm_bufs[spare];
            let pass_c = |(c, (fa, nb)): (usize, (&mut [i8], &mut [[f32; 3]]))| {
                let base = c * CHUNK;
                for (i, (out, nb)) in fa.iter_mut().zip(nb).enumerate() {
                    let v = base + i;
                    let nrm = if given {
                        *nb
                    } else {
                        let n = vf.normal(v, face_n);
                        *nb = n;
                        n
                    };
                    *out = match prev {
                        Some(pr) => facing(nrm, cur[v], pr[v]),
                        None => NEUTRAL,
                    };
                }
            };
            if par {
                self.facing
                    .par_chunks_mut(CHUNK)
                    .zip(nb.par_chunks_mut(CHUNK))
                    .enumerate()
                    .for_each(pass_c);
            } else {
                self.facing
                    .chunks_mut(CHUNK)
                    .zip(nb.chunks_mut(CHUNK))
                    .enumerate()
                    .for_each(pass_c);
            }
        }
        self.spare = std::mem::replace(&mut self.buf_of_slot[slot], spare);
        // Pass D: silhouette edge, state, ring element (and the birth element at n - 1).
        {
            let (row, prev_row): (&mut [u8], &mut [u8]) = if s == 1 {
                (&mut self.ring[..], &mut self.scratch_row)
            } else {
                let pslot = (slot + s - 1) % s;
                let (lo_slot, hi_slot) = (slot.min(pslot), slot.max(pslot));
                let (a, b) = self.ring.split_at_mut(hi_slot * nf);
                let (lo_row, hi_row) = (&mut a[lo_slot * nf..(lo_slot + 1) * nf], &mut b[..nf]);
                if slot > pslot {
                    (hi_row, lo_row)
                } else {
                    (lo_row, hi_row)
                }
            };
            let (facing_v, faces, mask) = (&self.facing, &self.loc.ifaces, self.mask.as_deref());
            let h = self.opts.hysteresis;
            let n = n as u32;
            type Rows<'a> = (((&'a mut [u8], &'a mut [Hot]), &'a mut [u8]), &'a mut [u8]);
            let pass_d = |(c, (((fades, hots), row), prow)): (usize, Rows<'_>)| {
                let base = c * CHUNK;
                for i in 0..fades.len() {
                    let f = base + i;
                    let on = mask.is_none_or(|m| m[f]);
                    let code = if on {
                        face_edge(facing_v, &faces[f])
                    } else {
                        NO_EDGE
                    };
                    if code == NO_EDGE && fades[i] as usize >= s {
                        continue; // no strip and no edge: nothing changes
                    }
                    let step = Step { code, s, h, n };
                    step.apply(&mut fades[i], &mut hots[i], &mut row[i], &mut prow[i]);
                }
            };
            if par {
                self.fade
                    .par_chunks_mut(CHUNK)
                    .zip(self.hot.par_chunks_mut(CHUNK))
                    .zip(row.par_chunks_mut(CHUNK))
                    .zip(prev_row.par_chunks_mut(CHUNK))
                    .enumerate()
                    .for_each(pass_d);
            } else {
                self.fade
                    .chunks_mut(CHUNK)
                    .zip(self.hot.chunks_mut(CHUNK))
                    .zip(row.chunks_mut(CHUNK))
                    .zip(prev_row.chunks_mut(CHUNK))
                    .enumerate()
                    .for_each(pass_d);
            }
        }
        self.updates += 1;
        Ok(())
    }
}

/// Float32 copies of `rows` scattered to `out[inv[i]]`, in parallel; true if a value is NaN,
/// inf or beyond `lim` in magnitude (then `out` is partly written: callers write only to a
/// spare buffer).
fn scatter_f32(rows: &[[f64; 3]], inv: &[u32], out: &mut [[f32; 3]], lim: f64, par: bool) -> bool {
    if !par {
        let mut bad = false;
        for (p, &dst) in rows.iter().zip(inv) {
            bad |= !(p[0].abs() <= lim && p[1].abs() <= lim && p[2].abs() <= lim);
            out[dst as usize] = [p[0] as f32, p[1] as f32, p[2] as f32];
        }
        return bad;
    }
    let out = SharedSlots(out.as_mut_ptr());
    rows.par_chunks(CHUNK)
        .zip(inv.par_chunks(CHUNK))
        .map(|(v, idx)| {
            let out = &out;
            let mut bad = false;
            for (p, &dst) in v.iter().zip(idx) {
                bad |= !(p[0].abs() <= lim && p[1].abs() <= lim && p[2].abs() <= lim);
                // SAFETY: `inv` is a permutation of 0..out.len(), so each slot is in bounds and
                // written by exactly one row: no two threads write the same slot.
                unsafe { *out.0.add(dst as usize) = [p[0] as f32, p[1] as f32, p[2] as f32] };
            }
            bad
        })
        .reduce(|| false, |a, b| a || b)
}

/// One polygon's state change at update `n` with silhouette edge `code` (or `NO_EDGE`).
struct Step {
    code: u8,
    s: usize,
    h: u32,
    n: u32,
}

impl Step {
    /// Writes the polygon's ring element for this update into `elem` and, at a birth, the
    /// element of the previous update into `prev_elem`.
    #[inline]
    fn apply(&self, fade: &mut u8, st: &mut Hot, elem: &mut u8, prev_elem: &mut u8) {
        let (code, s) = (self.code, self.s);
        let alive = (*fade as usize) < s;
        if code != NO_EDGE {
            if alive {
                *fade = fade.saturating_sub(1);
                st.run = (st.run as usize + 1).min(s) as u8;
            } else {
                *fade = 0;
                st.run = 2.min(s) as u8;
                *prev_elem = code;
            }
            st.last = code;
            st.last_on = self.n;
            *elem = code | ON_SILHOUETTE;
        } else if alive {
            let since = if st.last_on == NEVER {
                u32::MAX
            } else {
                self.n.wrapping_sub(st.last_on)
            };
            if since > self.h {
                *fade += 1;
            }
            if (*fade as usize) < s {
                st.run = (st.run as usize + 1).min(s) as u8;
                *elem = st.last;
            } else {
                st.run = 0;
            }
        }
    }
}
