//! Convex hulls of projected point sets and meshes, for the coverage model of the motion volume
//! ([`crate::volume_alpha`]).
//!
//! A dense mesh's projected hull is found from its rim: [`rim_points`] keeps only the vertices
//! where the projected surface folds over (the silhouette as seen from the eye), a few hundred of
//! the 42k vertices of an 80k-face sphere, and [`convex_hull`] then sorts those instead of all.
use rayon::prelude::*;

use crate::mesh::FaceNeighbors;

/// The faces and face neighbours of a closed, consistently wound 2-manifold mesh (see
/// [`crate::mesh::Mesh::face_neighbors`]), for [`rim_points`].
#[derive(Debug, Clone, Copy)]
pub struct Rim<'a> {
    pub faces: &'a [[u32; 3]],
    pub neighbors: &'a FaceNeighbors,
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

/// Akl-Toussaint: drop the points strictly inside the polygon of the extreme points in 32
/// directions (they cannot be on the hull), so that a dense mesh sorts only its rim (about a
/// tenth of a sphere's projected vertices).
pub fn discard_interior(pts: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    const K: usize = 32;
    if pts.len() < 4 * K {
        return pts;
    }
    let dirs: Vec<[f64; 2]> = (0..K)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / K as f64;
            [a.cos(), a.sin()]
        })
        .collect();
    let key = |p: [f64; 2], d: [f64; 2]| p[0] * d[0] + p[1] * d[1];
    // The point of largest p . d per direction (ties: the first), counter-clockwise.
    let ext = pts
        .par_chunks(8192)
        .map(|c| {
            let mut o = [c[0]; K];
            for p in &c[1..] {
                for (e, d) in o.iter_mut().zip(&dirs) {
                    if key(*p, *d) > key(*e, *d) {
                        *e = *p;
                    }
                }
            }
            o
        })
        .reduce_with(|mut a, b| {
            for ((e, x), d) in a.iter_mut().zip(b).zip(&dirs) {
                if key(x, *d) > key(*e, *d) {
                    *e = x;
                }
            }
            a
        })
        .expect("at least one chunk");
    let mut poly: Vec<[f64; 2]> = ext.to_vec();
    poly.dedup();
    while poly.len() > 1 && poly[0] == poly[poly.len() - 1] {
        poly.pop();
    }
    if poly.len() < 3 {
        return pts;
    }
    let inside = |p: &[f64; 2]| {
        (0..poly.len()).all(|i| {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]) > 0.0
        })
    };
    pts.into_par_iter().filter(|p| !inside(p)).collect()
}

/// Andrew's monotone chain: the convex hull, counter-clockwise, without collinear points.
pub fn convex_hull(pts: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    let mut pts = discard_interior(pts);
    pts.par_sort_unstable_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut h: Vec<[f64; 2]> = Vec::with_capacity(2 * pts.len());
    for pass in 0..2 {
        let start = h.len();
        let iter: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in iter {
            while h.len() >= start + 2 && cross(h[h.len() - 2], h[h.len() - 1], p) <= 0.0 {
                h.pop();
            }
            h.push(p);
        }
        h.pop();
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;

    #[test]
    fn hull_of_a_square_with_inner_points() {
        let h = convex_hull(vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [0.5, 0.5],
            [1.0, 1.0],
            [0.0, 1.0],
            [0.5, 0.0],
        ]);
        assert_eq!(h.len(), 4);
    }

    /// A closed, consistently wound UV sphere with `n` rings and `2n` segments, its vertices
    /// pushed in and out a little so that it is not convex and no projection is symmetric.
    fn sphere(n: usize) -> Mesh {
        let (v, f) = crate::test_meshes::uv_sphere(n, 2 * n);
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
        };
        // perspective views from several eyes (the lumpy sphere is not convex in 3D)
        for eye in [
            [0.3, 0.2, 4.0],
            [3.0, -1.0, 0.5],
            [0.0, 0.0, -2.5],
            [1.4, 1.3, 1.2],
        ] {
            let d = crate::mesh::normalize([-eye[0], -eye[1], -eye[2]]);
            let e1 = crate::mesh::normalize([d[1], -d[0], 0.0]);
            let e1 = if e1 == [0.0; 3] { [1.0, 0.0, 0.0] } else { e1 };
            let e2 = [
                d[1] * e1[2] - d[2] * e1[1],
                d[2] * e1[0] - d[0] * e1[2],
                d[0] * e1[1] - d[1] * e1[0],
            ];
            let proj: Vec<[f64; 2]> = mesh
                .vertices()
                .iter()
                .map(|p| {
                    let r = [p[0] - eye[0], p[1] - eye[1], p[2] - eye[2]];
                    let z = crate::mesh::dot(r, d);
                    [crate::mesh::dot(r, e1) / z, crate::mesh::dot(r, e2) / z]
                })
                .collect();
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
}
