//! The blur shell's state: options, construction, history buffers and per-polygon state.
use rayon::prelude::*;

use super::locality::Locality;
use crate::budget::Need;
use crate::contour::{check_values, NEUTRAL, NO_EDGE};
use crate::error::{Error, Result};
use crate::mesh::MAX_ELEMENTS;

/// Work items per rayon task of the update and build passes: fixed, so the split does not
/// depend on the thread count.
pub(super) const CHUNK: usize = 8192;

/// Edge-code bit: the element's edge was on the silhouette at its update.
pub const ON_SILHOUETTE: u8 = 4;
/// Largest `subdivisions` (the fade level is a `u8`).
pub const MAX_SUBDIVISIONS: u32 = 255;
/// Largest `hysteresis` (the count of updates off the silhouette is a saturating `u16`).
pub const MAX_HYSTERESIS: u32 = 65_000;

/// Shell options (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShellOptions {
    /// Ring elements per polygon, 1..=255: the strip's length in updates.
    pub subdivisions: u32,
    /// Updates off the silhouette before a strip starts to fade.
    pub hysteresis: u32,
    /// Alpha of a strip's base pair, in (0, 1].
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

/// The shell's colour: one RGBA for every strip, or the RGBA of each mesh vertex. The alpha
/// (in [0, 1]) scales the strip's own (`initial_alpha` fading along the strip): a translucent
/// object's trail is as translucent as the object.
#[derive(Debug, Clone, PartialEq)]
pub enum ShellColor {
    /// One RGBA for every strip.
    Uniform([f32; 4]),
    /// One RGBA per mesh vertex.
    PerVertex(Vec<[f32; 4]>),
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
pub(super) struct Hot {
    pub(super) last: u8,
    pub(super) run: u8,
    /// Update index of the last silhouette edge (`NEVER`: none); `since` is derived from it.
    pub(super) last_on: u32,
}

/// [`Hot::last_on`] of a polygon that never had a silhouette edge.
pub(super) const NEVER: u32 = u32::MAX;

impl Hot {
    pub(super) const INITIAL: Hot = Hot {
        last: NO_EDGE,
        run: 0,
        last_on: NEVER,
    };
}

/// The stateful blur shell of one mesh (fixed faces and vertex count).
#[derive(Debug)]
pub struct BlurShell {
    pub(super) faces: Vec<[u32; 3]>,
    pub(super) n_vertices: usize,
    pub(super) opts: ShellOptions,
    pub(super) mask: Option<Vec<bool>>,
    pub(super) color: ShellColor,
    /// Internal vertex and face order of the per-update passes (see [`Locality`]).
    pub(super) loc: Locality,
    pub(super) updates: u64,
    pub(super) facing: Vec<i8>,
    pub(super) face_n: Vec<[f32; 3]>,
    /// `subdivisions + 1` buffers of float32 positions: one per ring slot (`buf_of_slot`) and
    /// a spare that the next update fills, so a failed update leaves every snapshot intact.
    pub(super) pos_bufs: Vec<Vec<[f32; 3]>>,
    /// Raw float32 vertex normals per buffer: the given ones, or the unnormalised area-weighted
    /// ones the update computed for the facing test (stored as it goes, so build() reads them
    /// instead of recomputing face normals around every strip vertex).
    pub(super) nrm_bufs: Vec<Vec<[f32; 3]>>,
    pub(super) buf_of_slot: Vec<usize>,
    pub(super) spare: usize,
    /// Edge codes, slot-major (`slot * F + f`).
    pub(super) ring: Vec<u8>,
    /// With one subdivision the birth element shares the ring row; it goes here instead.
    pub(super) scratch_row: Vec<u8>,
    pub(super) fade: Vec<u8>,
    pub(super) hot: Vec<Hot>,
}

/// Meshes with fewer faces run updates and builds sequentially (see [`BlurShell::parallel`]).
pub const PAR_MIN_FACES: usize = 4 * CHUNK;

/// Fails naming `name` unless `a` has `n` rows of finite values within the silhouette's
/// float32 bounds.
pub(super) fn check_rows(a: &[[f64; 3]], n: usize, name: &'static str, par: bool) -> Result<()> {
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
    check_values(a, name, par)
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
        let bad_rgba = |c: &[f32; 4]| c.iter().any(|x| !x.is_finite() || *x < 0.0) || c[3] > 1.0;
        match &color {
            ShellColor::Uniform(c) if bad_rgba(c) => {
                return Err(Error::value(
                    "color",
                    "must be finite and >= 0, alpha in [0, 1]",
                ));
            }
            ShellColor::PerVertex(v) if v.len() != n_vertices => {
                return Err(Error::shape(
                    "color",
                    format!(
                        "expected one colour or {n_vertices} (one per vertex), got {}",
                        v.len()
                    ),
                ));
            }
            ShellColor::PerVertex(v) if v.iter().any(bad_rgba) => {
                return Err(Error::value(
                    "color",
                    "must be finite and >= 0, alpha in [0, 1]",
                ));
            }
            _ => {}
        }
        let s = opts.subdivisions as usize;
        let nf = faces.len();
        // Positions and normals (12 bytes each per vertex and buffer), the rings, per-face and
        // per-vertex state, checked against the memory budget before any is allocated.
        let (nv64, nf64, s64) = (n_vertices as u64, nf as u64, u64::from(opts.subdivisions));
        Need::new("BlurShell")
            .add(&[("n_vertices", nv64), ("subdivisions + 1", s64 + 1)], 24)?
            .add(&[("faces", nf64), ("subdivisions", s64)], 1)?
            .add(&[("faces", nf64)], 64)?
            .add(&[("n_vertices", nv64)], 16)?
            .check()?;
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
    pub(super) fn raw_normal(&self, buf: usize, iv: usize) -> [f32; 3] {
        self.nrm_bufs[buf][iv]
    }

    /// Whether updates and builds run their chunks on rayon's pool: only for meshes of at
    /// least `PAR_MIN_FACES` (32768) faces. Smaller ones run the same chunks in order on the calling
    /// thread (fork/join and hand-overs cost more than the work), with the same results.
    pub fn parallel(&self) -> bool {
        self.faces.len() >= PAR_MIN_FACES
    }

    /// The options the shell was made with.
    pub fn options(&self) -> ShellOptions {
        self.opts
    }
    /// The mesh's faces.
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }
    /// The mesh's vertex count.
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
}
