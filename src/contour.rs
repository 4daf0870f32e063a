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

use crate::mesh::{dot, face_normal, Mesh};
use crate::{Error, Result};

/// A contour edge: `edge` indexes the mesh adjacency, `(a, b)` is its orientation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ContourEdge {
    pub edge: u32,
    pub a: u32,
    pub b: u32,
}

pub(crate) fn check_vector(v: [f64; 3], name: &'static str) -> Result<()> {
    if v.iter().any(|x| !x.is_finite()) {
        return Err(Error::value(name, "is NaN or inf"));
    }
    Ok(())
}

/// Front (`true`) or back per face for the motion vector `m` (object space).
///
/// The vertex gathers dominate on meshes whose faces point far apart in the vertex array (an
/// icosphere's subdivision), so on x86_64 the vertices of the face `AHEAD` places on are
/// prefetched.
pub fn classify_faces(mesh: &Mesh, m: [f64; 3]) -> Vec<bool> {
    const CHUNK: usize = 8192;
    const AHEAD: usize = 24;
    let v = mesh.vertices();
    let faces = mesh.faces();
    let mut out = vec![false; faces.len()];
    out.par_chunks_mut(CHUNK)
        .enumerate()
        .for_each(|(ci, chunk)| {
            let base = ci * CHUNK;
            for (k, o) in chunk.iter_mut().enumerate() {
                let i = base + k;
                #[cfg(target_arch = "x86_64")]
                if let Some(g) = faces.get(i + AHEAD) {
                    for &x in g {
                        // SAFETY: `x` is a valid vertex index (checked by `Mesh::new`), so the pointer
                        // stays inside `v`; a prefetch has no other effect.
                        unsafe {
                            use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
                            _mm_prefetch(v.as_ptr().add(x as usize) as *const i8, _MM_HINT_T0);
                        }
                    }
                }
                *o = dot(face_normal(v, &faces[i]), m) >= 0.0;
            }
        });
    out
}

/// Whether each face is front-facing to a camera at `eye`: `n . (eye - a) > 0`, with vertices
/// placed by `place`.
pub fn camera_facing(
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

/// The oriented contour edges for a face classification, in adjacency (edge) order.
///
/// On a closed, consistently wound 2-manifold mesh this walks the faces over the cached
/// [`Mesh::face_neighbors`]: every edge from a front face to a back neighbour is marked with the
/// direction the front face runs it (the rule of the module docs, which it equals there), and
/// the marks are read in edge order. Otherwise it walks the edges.
pub fn contour_from_sides(mesh: &Mesh, front: &[bool]) -> Vec<ContourEdge> {
    if let Some(nbr) = mesh.face_neighbors() {
        use std::sync::atomic::{AtomicU8, Ordering::Relaxed};
        let adj = mesh.adjacency();
        // 0: not a contour edge; 1: runs higher -> lower in its front face; 2: lower -> higher.
        // Each contour edge has one front face, so each mark is written once.
        let marks: Vec<AtomicU8> = (0..adj.len()).map(|_| AtomicU8::new(0)).collect();
        mesh.faces()
            .par_iter()
            .zip(&nbr.faces)
            .zip(&nbr.edges)
            .zip(front)
            .with_min_len(4096)
            .for_each(|(((f, n), e), &fr)| {
                if fr {
                    for k in 0..3 {
                        if !front[n[k] as usize] {
                            marks[e[k] as usize]
                                .store(1 + u8::from(f[k] < f[(k + 1) % 3]), Relaxed);
                        }
                    }
                }
            });
        return marks
            .par_iter()
            .enumerate()
            .with_min_len(4096)
            .filter_map(|(e, mark)| {
                let [lo, hi] = adj.edges[e];
                match mark.load(Relaxed) {
                    0 => None,
                    1 => Some(ContourEdge {
                        edge: e as u32,
                        a: hi,
                        b: lo,
                    }),
                    _ => Some(ContourEdge {
                        edge: e as u32,
                        a: lo,
                        b: hi,
                    }),
                }
            })
            .collect();
    }
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
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let two = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let a = one.install(|| contour_edges(&m, [0.3, -0.2, 0.9], Some([3.0, 1.0, 2.0])).unwrap());
        let b = two.install(|| contour_edges(&m, [0.3, -0.2, 0.9], Some([3.0, 1.0, 2.0])).unwrap());
        assert_eq!(a, b);
    }

    #[test]
    fn nan_motion_is_an_error() {
        assert!(contour_edges(&cube(), [f64::NAN, 0.0, 0.0], None).is_err());
        assert!(contour_edges(&cube(), [1.0, 0.0, 0.0], Some([f64::INFINITY, 0.0, 0.0])).is_err());
    }
}
