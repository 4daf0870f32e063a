//! Contour edges (Wloka and Zeleznik, section 3.2): the edges between the faces that face the
//! motion vector (`n . m >= 0`, the *front*) and those that face away (`n . m < 0`, the *back*).
//!
//! `n` is the unnormalised face normal `(b - a) x (c - a)`; a degenerate face has `n = 0`, so
//! `n . m = 0` and it is front by the paper's `>=` rule (it is counted in the mesh stats).
//!
//! The rule for every edge, which is exactly the paper's on a closed, consistently wound mesh:
//! sum over the edge's front faces `+1` for a face that runs it from the lower to the higher
//! vertex index and `-1` otherwise (`net_front`), and the same over its back faces (`net_back`).
//! The edge is a contour edge when `net_front != 0` or `net_back != 0`, i.e. when the front or
//! the back part of the mesh has a border there. It is oriented as its front faces run it
//! (counter-clockwise), or against its back faces when its front faces cancel. So a boundary
//! edge (one face) is always a contour edge, oriented as its face when that face is front and
//! reversed otherwise; a non-manifold edge (three or more faces) is one when its front (or back)
//! windings do not cancel. With this orientation the joining quad `a0 b0 b1 a1` (trailing edge
//! at shutter open, leading edge at close) is wound outward.
use rayon::prelude::*;

use crate::error::check_vector;
use crate::error::Result;
use crate::mesh::{dot, face_normal, Mesh};
use crate::motion::Keyframe;

/// A contour edge: `edge` indexes the mesh adjacency, `(a, b)` is its orientation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ContourEdge {
    /// Index of the edge in the mesh adjacency.
    pub edge: u32,
    /// First vertex, as the edge is oriented.
    pub a: u32,
    /// Second vertex.
    pub b: u32,
}

/// Faces ahead of the one in hand whose corners [`prefetch_corners`] asks for.
const AHEAD: usize = 24;

/// Asks the CPU to load the corners of face `f` (if any) into cache: the face passes gather
/// vertices in face order, which a 42k-vertex mesh scatters over memory.
#[inline]
fn prefetch_corners(v: &[[f64; 3]], faces: &[[u32; 3]], f: usize) {
    #[cfg(target_arch = "x86_64")]
    if let Some(g) = faces.get(f) {
        for &x in g {
            // SAFETY: `x` is a valid vertex index (checked by `Mesh::new`), so the pointer stays
            // inside `v`; a prefetch has no other effect.
            unsafe {
                use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
                _mm_prefetch(v.as_ptr().add(x as usize) as *const i8, _MM_HINT_T0);
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (v, faces, f);
}

/// Front (`true`) or back per face for the motion vector `m` (object space): `n . m >= 0` with
/// `n` the raw face normal.
///
/// A mesh classified again (a rigid object, every frame) streams over its kept normals
/// ([`Mesh::repeated_face_normals_raw`]); the first call on a mesh (a deformed copy is used
/// once) computes each face's normal from its corners, prefetching the corners of the face
/// `AHEAD` places on (an icosphere's faces reach their vertices far apart in the array). Both
/// compute the same normal, so the classification is the same.
pub fn classify_faces(mesh: &Mesh, m: [f64; 3]) -> Vec<bool> {
    if let Some(normals) = mesh.repeated_face_normals_raw() {
        return normals
            .par_iter()
            .with_min_len(1 << 14)
            .map(|&n| dot(n, m) >= 0.0)
            .collect();
    }
    const CHUNK: usize = 8192;
    let v = mesh.vertices();
    let faces = mesh.faces();
    let mut out = vec![false; faces.len()];
    out.par_chunks_mut(CHUNK)
        .enumerate()
        .for_each(|(ci, chunk)| {
            let base = ci * CHUNK;
            for (k, o) in chunk.iter_mut().enumerate() {
                let i = base + k;
                prefetch_corners(v, faces, i + AHEAD);
                *o = dot(face_normal(v, &faces[i]), m) >= 0.0;
            }
        });
    out
}

/// [`classify_faces`] for `m` and, in the same pass over the faces (each face's corners
/// gathered once, prefetched), whether each face faces the camera at `eye` when placed by `close`
/// and by `open`: [`camera_facing`]'s test `n . (eye - a) > 0` made in object space, against the
/// eye brought back by each keyframe (`L^-1 (eye - t)`; a similarity with a positive
/// determinant keeps the sign), so nothing is placed. It can differ from the world-space test
/// only on faces edge-on to the eye within rounding.
pub fn classify_faces_seen(
    mesh: &Mesh,
    m: [f64; 3],
    eye: [f64; 3],
    close: &Keyframe,
    open: &Keyframe,
) -> (Vec<bool>, Vec<bool>, Vec<bool>) {
    const CHUNK: usize = 8192;
    let v = mesh.vertices();
    let faces = mesh.faces();
    let n = faces.len();
    let back = |k: &Keyframe| {
        let t = k.translation;
        k.inverse_vector([eye[0] - t[0], eye[1] - t[1], eye[2] - t[2]])
    };
    let (ec, eo) = (back(close), back(open));
    let (mut front, mut lead, mut trail) = (vec![false; n], vec![false; n], vec![false; n]);
    front
        .par_chunks_mut(CHUNK)
        .zip(lead.par_chunks_mut(CHUNK))
        .zip(trail.par_chunks_mut(CHUNK))
        .enumerate()
        .for_each(|(ci, ((fr, le), tr))| {
            let base = ci * CHUNK;
            for k in 0..fr.len() {
                let i = base + k;
                prefetch_corners(v, faces, i + AHEAD);
                let nf = face_normal(v, &faces[i]);
                let a = v[faces[i][0] as usize];
                fr[k] = dot(nf, m) >= 0.0;
                le[k] = dot(nf, [ec[0] - a[0], ec[1] - a[1], ec[2] - a[2]]) > 0.0;
                tr[k] = dot(nf, [eo[0] - a[0], eo[1] - a[1], eo[2] - a[2]]) > 0.0;
            }
        });
    (front, lead, trail)
}

/// [`classify_faces_seen`]'s camera tests alone, with its arithmetic, for a face split that is
/// already known (a [`ContourTable`](super::ContourTable)'s): whether each face faces the camera
/// at `eye` when placed by `close` and by `open`.
pub fn faces_seen(
    mesh: &Mesh,
    eye: [f64; 3],
    close: &Keyframe,
    open: &Keyframe,
) -> (Vec<bool>, Vec<bool>) {
    const CHUNK: usize = 8192;
    let v = mesh.vertices();
    let faces = mesh.faces();
    let back = |k: &Keyframe| {
        let t = k.translation;
        k.inverse_vector([eye[0] - t[0], eye[1] - t[1], eye[2] - t[2]])
    };
    let (ec, eo) = (back(close), back(open));
    let (mut lead, mut trail) = (vec![false; faces.len()], vec![false; faces.len()]);
    lead.par_chunks_mut(CHUNK)
        .zip(trail.par_chunks_mut(CHUNK))
        .enumerate()
        .for_each(|(ci, (le, tr))| {
            let base = ci * CHUNK;
            for k in 0..le.len() {
                let i = base + k;
                prefetch_corners(v, faces, i + AHEAD);
                let nf = face_normal(v, &faces[i]);
                let a = v[faces[i][0] as usize];
                le[k] = dot(nf, [ec[0] - a[0], ec[1] - a[1], ec[2] - a[2]]) > 0.0;
                tr[k] = dot(nf, [eo[0] - a[0], eo[1] - a[1], eo[2] - a[2]]) > 0.0;
            }
        });
    (lead, trail)
}

/// Whether each face is front-facing to a camera at `eye`: `n . (eye - a) > 0`, with vertices
/// placed by `place`.
fn camera_facing(
    mesh: &Mesh,
    eye: [f64; 3],
    place: impl Fn([f64; 3]) -> [f64; 3] + Sync,
) -> Vec<bool> {
    let v = mesh.vertices();
    mesh.faces()
        .par_iter()
        .with_min_len(4096)
        .map(|f| {
            let a = place(v[f[0] as usize]);
            let b = place(v[f[1] as usize]);
            let c = place(v[f[2] as usize]);
            let n = face_normal(&[a, b, c], &[0, 1, 2]);
            dot(n, [eye[0] - a[0], eye[1] - a[1], eye[2] - a[2]]) > 0.0
        })
        .collect()
}

/// Edges per chunk of the closed-mesh selection: a chunk-local edge index and its orientation
/// bit fit in a `u16`.
const EDGE_CHUNK: usize = 1 << 14;

/// The contour edges of a closed, consistently wound 2-manifold mesh (every edge has exactly
/// two half-edges, `[2e, 2e + 1]` in the adjacency), in edge order, each made by
/// `make(edge, a, b)` and written straight into the result.
///
/// Two parallel passes over fixed chunks of edges. The first compacts, without branches, each
/// chunk's contour edges into its part of a scratch list as `local index << 1 | direction`
/// (direction 1: lower -> higher, as its front face runs it) and counts them; the second writes
/// each chunk's edges at its prefix-sum offset of the result. The chunks are fixed, so the
/// result does not depend on the thread count.
fn closed_contour<T: Send>(
    mesh: &Mesh,
    front: &[bool],
    make: impl Fn(u32, u32, u32) -> T + Sync,
) -> Vec<T> {
    let adj = mesh.adjacency();
    let n = adj.len();
    debug_assert_eq!(adj.half_edges.len(), 2 * n);
    let mut picks = vec![0u16; n];
    let counts: Vec<usize> = picks
        .par_chunks_mut(EDGE_CHUNK)
        .zip(adj.half_edges.par_chunks(2 * EDGE_CHUNK))
        .zip(adj.forward.par_chunks(2 * EDGE_CHUNK))
        .map(|((pick, hs), fw)| {
            let mut j = 0;
            for (k, (h, f)) in hs.chunks_exact(2).zip(fw.chunks_exact(2)).enumerate() {
                let f0 = front[(h[0] / 3) as usize];
                let f1 = front[(h[1] / 3) as usize];
                // The front half-edge's direction: f[0] when face 0 is the front one.
                let fwd = if f0 { f[0] } else { f[1] };
                // j <= k < pick.len(): always written, kept only when the edge is a contour one.
                pick[j] = ((k as u16) << 1) | u16::from(fwd);
                j += usize::from(f0 != f1);
            }
            j
        })
        .collect();
    let total: usize = counts.iter().sum();
    let mut out: Vec<T> = Vec::with_capacity(total);
    {
        let mut parts = Vec::with_capacity(counts.len());
        let mut rest = &mut out.spare_capacity_mut()[..total];
        for &c in &counts {
            let (head, tail) = rest.split_at_mut(c);
            parts.push(head);
            rest = tail;
        }
        parts
            .into_par_iter()
            .zip(picks.par_chunks(EDGE_CHUNK))
            .enumerate()
            .for_each(|(ci, (dst, pick))| {
                let base = ci * EDGE_CHUNK;
                for (slot, &p) in dst.iter_mut().zip(pick) {
                    let e = base + (p >> 1) as usize;
                    let [lo, hi] = adj.edges[e];
                    let (a, b) = if p & 1 == 1 { (lo, hi) } else { (hi, lo) };
                    slot.write(make(e as u32, a, b));
                }
            });
    }
    // SAFETY: the chunk slices cover `out[..total]` exactly and chunk `ci` kept `counts[ci]`
    // picks, so the zip above wrote every slot once.
    unsafe { out.set_len(total) };
    out
}

/// The oriented contour edges for a face classification, in adjacency (edge) order.
///
/// On a closed, consistently wound 2-manifold mesh (cached [`Mesh::face_neighbors`] present)
/// every edge has one face on each side: it is a contour edge when exactly one of them is
/// front, oriented as that face runs it (the rule of the module docs, which it equals there).
/// Otherwise it walks each edge's faces.
pub fn contour_from_sides(mesh: &Mesh, front: &[bool]) -> Vec<ContourEdge> {
    if mesh.face_neighbors().is_some() {
        return closed_contour(mesh, front, |edge, a, b| ContourEdge { edge, a, b });
    }
    contour_by_edges(mesh, front)
}

/// The rule of the module docs on any mesh: walks every edge's faces.
pub(crate) fn contour_by_edges(mesh: &Mesh, front: &[bool]) -> Vec<ContourEdge> {
    let adj = mesh.adjacency();
    (0..adj.len())
        .into_par_iter()
        .with_min_len(4096)
        .filter_map(|e| {
            let (mut net_front, mut net_back) = (0i64, 0i64);
            for (&h, &fw) in adj.incident(e).iter().zip(adj.incident_forward(e)) {
                let s = if fw { 1 } else { -1 };
                if front[(h / 3) as usize] {
                    net_front += s;
                } else {
                    net_back += s;
                }
            }
            let [lo, hi] = adj.edges[e];
            let forward = if net_front != 0 {
                net_front > 0
            } else if net_back != 0 {
                net_back < 0
            } else {
                return None;
            };
            let (a, b) = if forward { (lo, hi) } else { (hi, lo) };
            Some(ContourEdge {
                edge: e as u32,
                a,
                b,
            })
        })
        .collect()
}

/// Keep the contour edges with at least one incident face flagged `visible`.
pub fn contour_line(mesh: &Mesh, edges: Vec<ContourEdge>, visible: &[bool]) -> Vec<ContourEdge> {
    let adj = mesh.adjacency();
    edges
        .into_par_iter()
        .filter(|c| {
            adj.incident(c.edge as usize)
                .iter()
                .any(|&h| visible[(h / 3) as usize])
        })
        .collect()
}

/// [`contour_edges`] as flat `a0, b0, a1, b1, ...` int64 pairs (the Python binding's (E,2)
/// array), written straight into the result on a closed mesh without a camera.
pub fn contour_pairs(mesh: &Mesh, m: [f64; 3], camera: Option<[f64; 3]>) -> Result<Vec<i64>> {
    if camera.is_none() && mesh.face_neighbors().is_some() {
        check_vector(m, "motion")?;
        let front = classify_faces(mesh, m);
        let mut pairs = closed_contour(mesh, &front, |_, a, b| [i64::from(a), i64::from(b)]);
        let (ptr, len, cap) = (pairs.as_mut_ptr(), pairs.len(), pairs.capacity());
        std::mem::forget(pairs);
        // SAFETY: `[i64; 2]` is two `i64` with the same alignment and no padding, so the
        // allocation of `cap` pairs is one of `2 * cap` i64 (same size and alignment).
        return Ok(unsafe { Vec::from_raw_parts(ptr as *mut i64, 2 * len, 2 * cap) });
    }
    Ok(contour_edges(mesh, m, camera)?
        .into_iter()
        .flat_map(|c| [i64::from(c.a), i64::from(c.b)])
        .collect())
}

/// The paper's contour edges for motion `m`; with `camera`, only the contour line (edges with
/// at least one adjacent face front-facing to the camera, `n . (camera - a) > 0`).
pub fn contour_edges(
    mesh: &Mesh,
    m: [f64; 3],
    camera: Option<[f64; 3]>,
) -> Result<Vec<ContourEdge>> {
    check_vector(m, "motion")?;
    let front = classify_faces(mesh, m);
    let edges = contour_from_sides(mesh, &front);
    match camera {
        None => Ok(edges),
        Some(eye) => {
            check_vector(eye, "camera_position")?;
            let visible = camera_facing(mesh, eye, |p| p);
            Ok(contour_line(mesh, edges, &visible))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> Mesh {
        let v: Vec<[f64; 3]> = (0..8)
            .map(|i| {
                [
                    (i >> 2 & 1) as f64 - 0.5,
                    (i >> 1 & 1) as f64 - 0.5,
                    (i & 1) as f64 - 0.5,
                ]
            })
            .collect();
        let f = vec![
            [0, 1, 3],
            [0, 3, 2],
            [4, 6, 7],
            [4, 7, 5],
            [0, 4, 5],
            [0, 5, 1],
            [2, 3, 7],
            [2, 7, 6],
            [0, 2, 6],
            [0, 6, 4],
            [1, 5, 7],
            [1, 7, 3],
        ];
        Mesh::new(v, f).unwrap()
    }

    #[test]
    fn cached_normals_classify_as_the_corners_do_and_deformed_copies_recompute() {
        let m = cube();
        let direct = |mesh: &Mesh, d: [f64; 3]| -> Vec<bool> {
            mesh.faces()
                .iter()
                .map(|f| dot(face_normal(mesh.vertices(), f), d) >= 0.0)
                .collect()
        };
        for d in [[1.0, 0.0, 0.0], [0.3, -0.7, 0.2], [0.0, 0.0, -1.0]] {
            // the first call computes from the corners, the later ones read the kept normals
            assert_eq!(classify_faces(&m, d), direct(&m, d));
        }
        // A deformed copy (mirrored in x) gets its own normals, not the original's.
        let mirrored: Vec<[f64; 3]> = m.vertices().iter().map(|v| [-v[0], v[1], v[2]]).collect();
        let copy = m.with_vertices(mirrored).unwrap();
        let d = [1.0, 0.2, 0.1];
        for _ in 0..3 {
            assert_eq!(classify_faces(&copy, d), direct(&copy, d));
        }
        assert_ne!(classify_faces(&copy, d), classify_faces(&m, d));
        assert!(m.repeated_face_normals_raw().is_some());
    }

    #[test]
    fn cube_along_x_has_the_back_square_as_contour() {
        let m = cube();
        let c = contour_edges(&m, [1.0, 0.0, 0.0], None).unwrap();
        // Sides have n . m = 0 (front), so the contour is the border of the -x face.
        assert_eq!(c.len(), 4);
        for e in &c {
            assert!(m.vertices()[e.a as usize][0] < 0.0 && m.vertices()[e.b as usize][0] < 0.0);
        }
    }

    #[test]
    fn diagonal_motion_gives_a_hexagon_and_reversal_flips_it() {
        let m = cube();
        let c = contour_edges(&m, [1.0, 2.0, 3.0], None).unwrap();
        assert_eq!(c.len(), 6);
        let r = contour_edges(&m, [-1.0, -2.0, -3.0], None).unwrap();
        let flipped: Vec<_> = c.iter().map(|e| (e.b, e.a)).collect();
        let got: Vec<_> = r.iter().map(|e| (e.a, e.b)).collect();
        assert_eq!(flipped, got);
    }

    #[test]
    fn contour_is_thread_count_independent() {
        let m = cube();
        let a = crate::on_threads(1, || {
            contour_edges(&m, [0.3, -0.2, 0.9], Some([3.0, 1.0, 2.0])).unwrap()
        });
        let b = crate::on_threads(2, || {
            contour_edges(&m, [0.3, -0.2, 0.9], Some([3.0, 1.0, 2.0])).unwrap()
        });
        assert_eq!(a, b);
    }

    /// A closed torus grid of `n x n` quads (two triangles each), wound outward.
    fn torus(n: u32) -> Mesh {
        let tau = std::f64::consts::TAU;
        let mut v = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let (u, w) = (tau * i as f64 / n as f64, tau * j as f64 / n as f64);
                // A little irregular, so some faces are far from any tie.
                let r = 1.0 + 0.3 * w.cos() + 0.01 * ((i * 7 + j * 13) % 5) as f64;
                v.push([r * u.cos(), r * u.sin(), 0.3 * w.sin()]);
            }
        }
        let id = |i: u32, j: u32| (i % n) * n + (j % n);
        let mut f = Vec::new();
        for i in 0..n {
            for j in 0..n {
                f.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                f.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        Mesh::new(v, f).unwrap()
    }

    #[test]
    fn closed_edge_walk_equals_the_general_rule_over_several_chunks() {
        let mesh = torus(120);
        assert!(mesh.face_neighbors().is_some());
        assert!(mesh.adjacency().len() > 2 * EDGE_CHUNK);
        for m in [
            [0.3, -0.2, 0.9],
            [1.0, 0.0, 0.0],
            [0.0, 0.0, -1.0],
            [-2.0, 5.0, 0.1],
        ] {
            let front = classify_faces(&mesh, m);
            let general = contour_by_edges(&mesh, &front);
            assert!(general.len() > 100);
            let fast = contour_from_sides(&mesh, &front);
            assert_eq!(fast, general);
            let flat: Vec<i64> = general
                .iter()
                .flat_map(|c| [i64::from(c.a), i64::from(c.b)])
                .collect();
            let p1 = crate::on_threads(1, || contour_pairs(&mesh, m, None).unwrap());
            let p2 = crate::on_threads(2, || contour_pairs(&mesh, m, None).unwrap());
            assert_eq!(p1, flat);
            assert_eq!(p2, flat);
        }
    }

    #[test]
    fn object_space_sides_agree_with_the_world_space_tests() {
        let mesh = torus(100);
        let turn = |a: f64, s: f64, t: [f64; 3]| {
            let (sn, c) = a.sin_cos();
            let m = [
                [s * c, 0.0, s * sn, t[0]],
                [0.0, s, 0.0, t[1]],
                [-s * sn, 0.0, s * c, t[2]],
                [0.0, 0.0, 0.0, 1.0],
            ];
            Keyframe::from_matrix(&m, 0).unwrap()
        };
        let (m, eye) = ([0.3, -0.2, 0.9], [0.4, 1.5, 3.0]);
        let world = |k: &Keyframe, tests: &[bool]| {
            // Faces edge-on to the eye within 1e-9 may go either way.
            let (mut checked, mut agree) = (0, 0);
            for (f, &got) in mesh.faces().iter().zip(tests) {
                let p = f.map(|i| k.point(mesh.vertices()[i as usize]));
                let n = face_normal(&p, &[0, 1, 2]);
                let r = [eye[0] - p[0][0], eye[1] - p[0][1], eye[2] - p[0][2]];
                let c = dot(n, r);
                if c.abs() > 1e-9 * dot(n, n).sqrt() * dot(r, r).sqrt() {
                    checked += 1;
                    agree += usize::from((c > 0.0) == got);
                }
            }
            (checked, agree)
        };
        for (open, close) in [
            (
                Keyframe::translate([0.0; 3]),
                Keyframe::translate([0.7, -0.2, 0.1]),
            ),
            (
                turn(0.1, 1.0, [0.0, 0.0, -1.0]),
                turn(0.9, 1.3, [0.5, 0.3, -1.2]),
            ),
        ] {
            let got = crate::on_threads(1, || classify_faces_seen(&mesh, m, eye, &close, &open));
            let two = crate::on_threads(2, || classify_faces_seen(&mesh, m, eye, &close, &open));
            assert!(got == two);
            assert_eq!(got.0, classify_faces(&mesh, m));
            for (k, tests) in [(&close, &got.1), (&open, &got.2)] {
                let (checked, agree) = world(k, tests);
                assert!(checked > mesh.faces().len() * 99 / 100, "{checked}");
                assert_eq!(checked, agree);
                // and the camera_facing test itself
                let w = camera_facing(&mesh, eye, |p| k.point(p));
                let differ = w.iter().zip(tests.iter()).filter(|(a, b)| a != b).count();
                assert!(differ <= mesh.faces().len() - checked);
            }
            assert!(got.1 != got.2 && got.1.iter().any(|x| *x) && got.2.iter().any(|x| !*x));
        }
    }

    #[test]
    fn nan_motion_is_an_error() {
        assert!(contour_edges(&cube(), [f64::NAN, 0.0, 0.0], None).is_err());
        assert!(contour_edges(&cube(), [1.0, 0.0, 0.0], Some([f64::INFINITY, 0.0, 0.0])).is_err());
    }
}
