//! The projected rim of a closed mesh, for the convex hulls of the motion volume's coverage
//! model (see `hulls.rs`).
//!
//! A dense mesh's projected hull is found from its rim: [`rim_points`] keeps only the vertices
//! where the projected surface folds over (the silhouette as seen from the eye), a few hundred of
//! the 42k vertices of an 80k-face sphere, and the convex hull then sorts those instead of all.
//! [`rim_candidates`] finds the faces that can lie on the rim of several views in one pass over
//! the mesh's cached [`FacePlanes`] (no projection), and [`rim_points_of`] gives exactly
//! [`rim_points`]'s output from those faces alone (about 2% of the sphere's faces).
use rayon::prelude::*;

use crate::mesh::{dot, FaceNeighbors, FacePlanes};

/// The faces and face neighbours of a closed, consistently wound 2-manifold mesh (see
/// [`crate::mesh::Mesh::face_neighbors`]), for [`rim_points`]; with the mesh's [`FacePlanes`],
/// [`rim_candidates`] can pick the few faces near a view's rim without projecting the mesh.
#[derive(Debug, Clone, Copy)]
pub struct Rim<'a> {
    pub faces: &'a [[u32; 3]],
    pub neighbors: &'a FaceNeighbors,
    pub planes: Option<&'a FacePlanes>,
}

/// A face counts as facing (or facing away from) a view only when the cosine between its normal
/// and the view ray exceeds this.
pub const MARGIN: f64 = 1e-2;

/// A view of [`rim_candidates`] in the mesh's object space: a perspective eye, or the direction
/// of an orthographic view.
#[derive(Debug, Clone, Copy)]
pub enum ObjectView {
    Eye([f64; 3]),
    Direction([f64; 3]),
}

/// For each view, the faces (increasing) outside of which [`rim_points`] keeps nothing: every
/// face that is not robustly facing or robustly facing away from the view (cosine within
/// [`MARGIN`], or a sliver), and every face with a neighbour in another state than its own.
///
/// A face outside the list and its three neighbours all robustly face the same way; when the
/// projection keeps the faces' orientations apart from degenerate (see
/// `hulls.rs`'s conditions), their projected orientations are then equal and non-zero,
/// so [`rim_points`] keeps nothing from that face, and [`rim_points_of`] over the list gives its
/// exact output. Fixed chunks: the same for any thread count.
pub fn rim_candidates(rim: Rim, planes: &FacePlanes, views: &[ObjectView]) -> Vec<Vec<u32>> {
    const CHUNK: usize = 4096;
    let mut out = Vec::with_capacity(views.len());
    for group in views.chunks(4) {
        let c = planes.center;
        let params: Vec<([f32; 3], f32, f32)> = group
            .iter()
            .map(|v| match *v {
                ObjectView::Eye(e) => {
                    let w = [e[0] - c[0], e[1] - c[1], e[2] - c[2]];
                    let r = dot(w, w).sqrt() + planes.radius;
                    (w.map(|x| x as f32), 1.0, (MARGIN * r) as f32)
                }
                ObjectView::Direction(d) => {
                    let r = dot(d, d).sqrt();
                    (d.map(|x| x as f32), 0.0, (MARGIN * r) as f32)
                }
            })
            .collect();
        // 2 bits per view: 0 facing, 1 facing away (either sign convention), 2 not robust.
        let codes: Vec<u8> = planes
            .planes()
            .par_iter()
            .with_min_len(CHUNK)
            .map(|p| {
                let mut code = 0u8;
                for (h, (w, s, tau)) in params.iter().enumerate() {
                    let g = p[0] * w[0] + p[1] * w[1] + p[2] * w[2] - s * p[3];
                    let k = if g > *tau {
                        0
                    } else if g < -*tau {
                        1
                    } else {
                        2
                    };
                    code |= k << (2 * h);
                }
                code
            })
            .collect();
        let nb = &rim.neighbors.faces;
        let chunks: Vec<Vec<Vec<u32>>> = codes
            .par_chunks(CHUNK)
            .enumerate()
            .map(|(ci, cs)| {
                let mut lists = vec![Vec::new(); group.len()];
                for (k, &code) in cs.iter().enumerate() {
                    let i = ci * CHUNK + k;
                    let n = nb[i].map(|g| codes[g as usize]);
                    let unsafe_any = (0..group.len()).any(|h| (code >> (2 * h)) & 3 == 2);
                    if !unsafe_any && n.iter().all(|&x| x == code) {
                        continue;
                    }
                    for (h, list) in lists.iter_mut().enumerate() {
                        let own = (code >> (2 * h)) & 3;
                        if own == 2 || n.iter().any(|&x| (x >> (2 * h)) & 3 != own) {
                            list.push(i as u32);
                        }
                    }
                }
                lists
            })
            .collect();
        for h in 0..group.len() {
            out.push(chunks.iter().flat_map(|l| l[h].iter().copied()).collect());
        }
    }
    out
}

/// [`rim_points`] restricted to the faces `candidates` (increasing; from [`rim_candidates`]),
/// with `point(v)` the projection of vertex `v` (evaluated for the candidates' corners only).
pub fn rim_points_of(
    rim: Rim,
    candidates: &[u32],
    point: impl Fn(u32) -> [f64; 2] + Sync,
) -> Vec<[f64; 2]> {
    let faces = rim.faces;
    let corners: Vec<[[f64; 2]; 3]> = candidates
        .par_iter()
        .with_min_len(256)
        .map(|&i| faces[i as usize].map(&point))
        .collect();
    // 2: not a candidate, so never `-s` below.
    let mut sign = vec![2i8; faces.len()];
    for (&i, p) in candidates.iter().zip(&corners) {
        sign[i as usize] = orientation(p[0], p[1], p[2]);
    }
    let mut out = Vec::new();
    for (&i, p) in candidates.iter().zip(&corners) {
        let s = sign[i as usize];
        if s == 0 {
            out.extend(p);
            continue;
        }
        for k in 0..3 {
            let g = rim.neighbors.faces[i as usize][k];
            if g > i && sign[g as usize] == -s {
                out.push(p[k]);
                out.push(p[(k + 1) % 3]);
            }
        }
    }
    out
}

/// Sign of the projected triangle's orientation: +1, -1, or 0 when it is within rounding of
/// degenerate (relative 1e-9 of its edge lengths) or not finite.
#[inline]
fn orientation(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> i8 {
    let (u, v) = ([b[0] - a[0], b[1] - a[1]], [c[0] - a[0], c[1] - a[1]]);
    let cr = u[0] * v[1] - u[1] * v[0];
    // |cr| > 1e-9 |u| |v|, without square roots
    let big = cr * cr > 1e-18 * ((u[0] * u[0] + u[1] * u[1]) * (v[0] * v[0] + v[1] * v[1]));
    if big && cr > 0.0 {
        1
    } else if big && cr < 0.0 {
        -1
    } else {
        0
    }
}

/// The projected vertices `proj` (one per mesh vertex, every vertex in front of the eye) that can
/// be vertices of the convex hull of all of `proj`: the ends of every edge whose two faces project
/// with opposite orientations (one faces the eye, one faces away) and the corners of every face
/// that projects degenerate; points may repeat.
///
/// Why no hull vertex is lost: around a vertex of a closed, consistently wound 2-manifold mesh
/// the faces form closed fans. If every face of a fan projects with the same strict
/// orientation, the projected fan winds around the vertex's image and covers a neighbourhood of
/// it, so that image is interior to the union of the projected faces, hence not a vertex of
/// their hull. Otherwise two consecutive faces of the fan (sharing an edge at the vertex) have
/// different signs, or one has sign 0, and the vertex is kept.
pub fn rim_points(rim: Rim, proj: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let faces = rim.faces;
    let sign: Vec<i8> = faces
        .par_iter()
        .map(|f| {
            orientation(
                proj[f[0] as usize],
                proj[f[1] as usize],
                proj[f[2] as usize],
            )
        })
        .collect();
    (0..faces.len())
        .into_par_iter()
        .with_min_len(4096)
        .fold(Vec::new, |mut out, i| {
            let (f, s) = (faces[i], sign[i]);
            if s == 0 {
                out.extend(f.map(|v| proj[v as usize]));
                return out;
            }
            for k in 0..3 {
                let g = rim.neighbors.faces[i][k] as usize;
                // each edge once, from its lower face; a degenerate partner emits itself
                if g > i && sign[g] == -s {
                    out.push(proj[f[k] as usize]);
                    out.push(proj[f[(k + 1) % 3] as usize]);
                }
            }
            out
        })
        .reduce(Vec::new, |mut a, b| {
            a.extend(b);
            a
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;
    use crate::volume::hulls::convex_hull;

    /// A closed, consistently wound UV sphere with `n` rings and `2n` segments, its vertices
    /// pushed in and out a little so that it is not convex and no projection is symmetric.
    fn sphere(n: usize) -> Mesh {
        let (v, f) = crate::mesh::uv_sphere(n, 2 * n);
        let v = v
            .iter()
            .enumerate()
            .map(|(k, p)| p.map(|x| x * (1.0 + 0.004 * ((7 * k) % 5) as f64)))
            .collect();
        Mesh::new(v, f).unwrap()
    }

    #[test]
    fn the_rim_keeps_every_hull_vertex_of_a_closed_mesh() {
        let mesh = sphere(24);
        let nb = mesh.face_neighbors().expect("closed sphere");
        let rim = Rim {
            faces: mesh.faces(),
            neighbors: nb,
            planes: None,
        };
        // perspective views from several eyes (the lumpy sphere is not convex in 3D)
        for eye in [
            [0.3, 0.2, 4.0],
            [3.0, -1.0, 0.5],
            [0.0, 0.0, -2.5],
            [1.4, 1.3, 1.2],
        ] {
            let proj = perspective(&mesh, eye);
            let kept = rim_points(rim, &proj);
            let mut distinct = kept.clone();
            distinct.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
            distinct.dedup();
            assert!(
                distinct.len() < proj.len() / 4,
                "{} of {}",
                distinct.len(),
                proj.len()
            );
            assert_eq!(convex_hull(kept), convex_hull(proj.clone()), "eye {eye:?}");
        }
    }

    /// A unit view direction along `dir` and two unit axes across it.
    fn basis(dir: [f64; 3]) -> ([f64; 3], [f64; 3], [f64; 3]) {
        let d = crate::mesh::normalize(dir);
        let e1 = crate::mesh::normalize([d[1], -d[0], 0.0]);
        let e1 = if e1 == [0.0; 3] { [1.0, 0.0, 0.0] } else { e1 };
        let e2 = [
            d[1] * e1[2] - d[2] * e1[1],
            d[2] * e1[0] - d[0] * e1[2],
            d[0] * e1[1] - d[1] * e1[0],
        ];
        (d, e1, e2)
    }

    /// The projection of the test above: perspective from `eye` towards the origin.
    fn perspective(mesh: &Mesh, eye: [f64; 3]) -> Vec<[f64; 2]> {
        let (d, e1, e2) = basis([-eye[0], -eye[1], -eye[2]]);
        mesh.vertices()
            .iter()
            .map(|p| {
                let r = [p[0] - eye[0], p[1] - eye[1], p[2] - eye[2]];
                let z = crate::mesh::dot(r, d);
                [crate::mesh::dot(r, e1) / z, crate::mesh::dot(r, e2) / z]
            })
            .collect()
    }

    #[test]
    fn rim_candidates_give_exactly_the_rim_points() {
        let mesh = sphere(64);
        assert!(mesh.faces().len() > 4096, "several chunks");
        let nb = mesh.face_neighbors().expect("closed sphere");
        let planes = FacePlanes::new(mesh.vertices(), mesh.faces());
        let rim = Rim {
            faces: mesh.faces(),
            neighbors: nb,
            planes: Some(&planes),
        };
        let eyes = [
            [0.3, 0.2, 4.0],
            [3.0, -1.0, 0.5],
            [0.0, 0.0, -2.5],
            [1.4, 1.3, 1.2],
            [40.0, 3.0, -7.0],
        ];
        let views: Vec<ObjectView> = eyes.iter().map(|e| ObjectView::Eye(*e)).collect();
        let one = crate::on_threads(1, || rim_candidates(rim, &planes, &views));
        let two = crate::on_threads(2, || rim_candidates(rim, &planes, &views));
        assert_eq!(one, two);
        for (eye, cand) in eyes.iter().zip(&one) {
            let proj = perspective(&mesh, *eye);
            let fast = rim_points_of(rim, cand, |v| proj[v as usize]);
            assert_eq!(fast, rim_points(rim, &proj), "eye {eye:?}");
        }
        // Orthographic views along a direction: the projection onto a plane across it.
        for dir in [[0.0, 0.0, -1.0], [0.6, -0.8, 0.0], [0.3, 0.5, 0.81]] {
            let (d, e1, e2) = basis(dir);
            let proj: Vec<[f64; 2]> = mesh
                .vertices()
                .iter()
                .map(|p| [crate::mesh::dot(*p, e1), crate::mesh::dot(*p, e2)])
                .collect();
            let cand = &rim_candidates(rim, &planes, &[ObjectView::Direction(d)])[0];
            let fast = rim_points_of(rim, cand, |v| proj[v as usize]);
            assert_eq!(fast, rim_points(rim, &proj), "direction {dir:?}");
        }
    }

    #[test]
    fn a_smooth_mesh_examines_few_faces() {
        let (v, f) = crate::mesh::uv_sphere(64, 128);
        let mesh = Mesh::new(v, f).unwrap();
        let planes = FacePlanes::new(mesh.vertices(), mesh.faces());
        let rim = Rim {
            faces: mesh.faces(),
            neighbors: mesh.face_neighbors().unwrap(),
            planes: Some(&planes),
        };
        for eye in [[3.0, -1.0, 0.5], [0.3, 0.2, 4.0], [40.0, 3.0, -7.0]] {
            let cand = &rim_candidates(rim, &planes, &[ObjectView::Eye(eye)])[0];
            assert!(cand.len() < mesh.faces().len() / 8, "{}", cand.len());
            let proj = perspective(&mesh, eye);
            let fast = rim_points_of(rim, cand, |v| proj[v as usize]);
            assert_eq!(fast, rim_points(rim, &proj), "eye {eye:?}");
        }
    }

    #[test]
    fn slivers_are_always_candidates() {
        // A tetrahedron with one face squashed to a sliver is examined from every view.
        let v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.5, 1e-4, 0.0],
            [0.4, 0.3, 1.0],
        ];
        let f = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let mesh = Mesh::new(v, f).unwrap();
        let planes = FacePlanes::new(mesh.vertices(), mesh.faces());
        assert!(planes.planes()[0][3].is_nan() && !planes.planes()[1][3].is_nan());
        let rim = Rim {
            faces: mesh.faces(),
            neighbors: mesh.face_neighbors().unwrap(),
            planes: Some(&planes),
        };
        let c = rim_candidates(rim, &planes, &[ObjectView::Eye([0.3, 0.2, 5.0])]);
        assert!(c[0].contains(&0));
    }
}
