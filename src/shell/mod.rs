//! Blur shells for deforming meshes (Jones and Keyser, "Real-Time Geometric Motion Blur for a
//! Deforming Polygonal Mesh"): the silhouette of motion, per-polygon history rings, hysteresis
//! and fading.
//!
//! A [`BlurShell`] is fed the mesh's world positions at each *update* and builds, on demand, a
//! shell of quad strips attached to the current mesh. The rules (the paper leaves some open;
//! each choice is stated here, in the Python docstring, and tested):
//!
//! - **Silhouette of motion** ([`motion_silhouette`](crate::motion_silhouette)): a moving vertex is front when
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
//!   (`locality.rs`), face normals, vertex normals and facing, then the per-polygon
//!   step, which reads one fade byte per polygon and touches nothing else for polygons without
//!   a strip or an edge. No allocation per update. Meshes under `PAR_MIN_FACES` faces run
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
//!
//! Files: `blur_shell.rs` (options, state, construction), `update.rs` (the update passes),
//! `build.rs` (the shell mesh), `locality.rs` (the internal vertex and face order).
mod blur_shell;
mod build;
mod history;
mod locality;
#[cfg(test)]
mod tests;
mod update;

pub use blur_shell::{
    BlurShell, FaceState, ShellColor, ShellOptions, MAX_HYSTERESIS, MAX_SUBDIVISIONS, ON_SILHOUETTE,
};
pub use build::{BuildPlan, ShellMesh, ShellOut};
