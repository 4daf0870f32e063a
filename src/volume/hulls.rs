//! The projected hulls of the coverage model (`coverage.rs`): the view's projection, and one
//! convex hull of the mesh's image per placement, taken over the rim of a closed mesh
//! ([`rim_points`]).
//!
//! For a dense closed mesh the faces that can lie on a placement's rim are first picked without
//! projecting anything ([`rim_candidates`], from the mesh's cached face planes),
//! when the view keeps robustly oriented faces robustly apart from degenerate (`object_view`);
//! the hull is then exactly the one of every projected vertex's rim, from a few thousand
//! projections instead of one per vertex and placement.
use rayon::prelude::*;

use super::rim::{rim_candidates, rim_points, rim_points_of, ObjectView, Rim, MARGIN};
use crate::mesh::{dot, FacePlanes, SLIVER};
use crate::motion::Keyframe;

/// Image-plane coordinates: `(p . e1, p . e2)`, or with an eye the perspective ones
/// `((p - eye) . e1, (p - eye) . e2) / ((p - eye) . d)` (depth clamped to a tiny positive value
/// for points at or behind the eye).
#[inline]
pub(super) fn project(
    eye: Option<[f64; 3]>,
    d: [f64; 3],
    e1: [f64; 3],
    e2: [f64; 3],
    p: [f64; 3],
) -> [f64; 2] {
    match eye {
        None => [dot(p, e1), dot(p, e2)],
        Some(e) => {
            let r = [p[0] - e[0], p[1] - e[1], p[2] - e[2]];
            let (a, rr) = (dot(r, d), dot(r, r));
            // `a` is the clamped depth itself when a^2 clearly exceeds (1e-9 |r|)^2 (no root).
            let z = if a > 1e-150 && a * a > 2e-18 * rr {
                a
            } else {
                a.max(1e-9 * rr.sqrt()).max(1e-300)
            };
            [dot(r, e1) / z, dot(r, e2) / z]
        }
    }
}

/// The object-space view of `rim_candidates` for the placement `f` of a mesh with planes
/// `planes`, or `None` when the projection does not keep robustly oriented faces robustly
/// apart from degenerate (then every vertex is projected).
///
/// For a face of sine `s` at its first corner whose normal makes a cosine of at least `c` with
/// the view ray, the projected triangle's sine at that corner is at least
/// `c s (z_lo / z_hi)^2 / (1 + tan^2)` (perspective: depths `z` along `d` in `[z_lo, z_hi]` over
/// the bounding sphere, `tan` the largest tangent of the angle to `d`); `rim_points` calls a
/// triangle degenerate below 1e-9, so the bound must stay above 1e-7. Every vertex must also be
/// in front of the eye (as `rim_points` requires), with a margin.
fn object_view(
    f: &Keyframe,
    planes: &FacePlanes,
    eye: Option<[f64; 3]>,
    d: [f64; 3],
) -> Option<ObjectView> {
    let inv = f.mat3().inverse();
    let obj = |w: [f64; 3]| inv.mul_vec3(glam::DVec3::from_array(w)).to_array();
    let Some(e) = eye else {
        return Some(ObjectView::Direction(obj(d)));
    };
    let scale = f.mat3().determinant().cbrt();
    let c = f.point(planes.center);
    let rad = planes.radius * scale;
    let r = [c[0] - e[0], c[1] - e[1], c[2] - e[2]];
    let dist = dot(r, r).sqrt();
    let zc = dot(r, d);
    let in_front = zc - rad > 1e-5 * (dist + rad) && rad < dist;
    if !in_front {
        return None;
    }
    let angle = (zc / dist).clamp(-1.0, 1.0).acos() + (rad / dist).asin();
    if angle >= 1.4 {
        return None;
    }
    let ratio = (zc - rad) / (zc + rad);
    let bound = MARGIN * SLIVER * ratio * ratio / (1.0 + angle.tan().powi(2));
    let t = f.translation;
    (bound > 1e-7).then(|| ObjectView::Eye(obj([e[0] - t[0], e[1] - t[1], e[2] - t[2]])))
}

/// The convex hull of the projected `vertices` at each placement (`basis`: `d, e1, e2`). With
/// `rim`, over the rim points only when every vertex is in front of the eye: from the faces
/// [`rim_candidates`] picks when the mesh has planes and [`object_view`] allows, else from
/// every projected vertex.
pub(crate) fn hulls_of(
    vertices: &[[f64; 3]],
    rim: Option<Rim>,
    placements: &[Keyframe],
    eye: Option<[f64; 3]>,
    basis: [[f64; 3]; 3],
) -> Vec<Vec<[f64; 2]>> {
    let [d, e1, e2] = basis;
    let proj = |p: [f64; 3]| project(eye, d, e1, e2, p);
    // The projected vertices, and whether every one is in front of the eye (depth along `d`
    // above 1e-6 of its distance; the projection clamps the others).
    let front_of = |p: [f64; 3]| match eye {
        None => true,
        Some(e) => {
            let r = [p[0] - e[0], p[1] - e[1], p[2] - e[2]];
            dot(r, d) > 1e-6 * dot(r, r).sqrt()
        }
    };
    let project_all = |f: &Keyframe| -> (Vec<[f64; 2]>, bool) {
        let f = f.placer();
        let both: Vec<([f64; 2], bool)> = vertices
            .par_iter()
            .map(|v| {
                let p = f.point(*v);
                (proj(p), front_of(p))
            })
            .collect();
        let front = both.iter().all(|b| b.1);
        (both.into_iter().map(|b| b.0).collect(), front)
    };
    let views: Vec<Option<ObjectView>> = placements
        .iter()
        .map(|f| {
            let planes = rim.and_then(|r| r.planes)?;
            object_view(f, planes, eye, d)
        })
        .collect();
    let picked: Vec<ObjectView> = views.iter().flatten().copied().collect();
    let candidates = match (rim, rim.and_then(|r| r.planes)) {
        (Some(r), Some(p)) if !picked.is_empty() => rim_candidates(r, p, &picked),
        _ => Vec::new(),
    };
    // The k-th placement with a view takes the k-th candidate list.
    let slot: Vec<usize> = views
        .iter()
        .scan(0, |k, v| {
            let slot = *k;
            *k += usize::from(v.is_some());
            Some(slot)
        })
        .collect();
    // Placements in parallel (each hull is small work with little parallelism of its own).
    placements
        .par_iter()
        .zip(&views)
        .zip(&slot)
        .map(|((f, view), &k)| match (view, rim) {
            (Some(_), Some(rim)) => {
                let f = f.placer();
                convex_hull(rim_points_of(rim, &candidates[k], |v| {
                    proj(f.point(vertices[v as usize]))
                }))
            }
            _ => match (project_all(f), rim) {
                ((pts, true), Some(rim)) => convex_hull(rim_points(rim, &pts)),
                ((pts, _), _) => convex_hull(pts),
            },
        })
        .collect()
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
    use crate::motion::Path;
    use crate::volume::coverage::CoverageModel;
    use crate::volume::filter::Filter;

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

    #[test]
    fn rim_candidates_leave_the_model_unchanged() {
        let (v, f) = crate::mesh::uv_sphere(40, 80);
        let mesh = crate::mesh::Mesh::new(v, f).unwrap();
        let nb = mesh.face_neighbors().unwrap();
        let rim = |planes| Rim {
            faces: mesh.faces(),
            neighbors: nb,
            planes,
        };
        let turn = |a: f64, t: [f64; 3]| {
            let (s, c) = a.sin_cos();
            [
                [c, -s, 0.0, t[0]],
                [s, c, 0.0, t[1]],
                [0.0, 0.0, 1.0, t[2]],
                [0.0, 0.0, 0.0, 1.0],
            ]
        };
        let paths = [
            Path::translation([2.0, 0.7, -0.3]).unwrap(),
            Path::from_matrices(&[turn(0.0, [0.0; 3]), turn(0.7, [1.0, 0.2, 0.0])]).unwrap(),
        ];
        for path in &paths {
            // Towards the object (rim candidates), far off it (every vertex projected), and
            // orthographic.
            for (eye, view, fast) in [
                (Some([0.3, 0.1, 6.0]), [-0.05, 0.0, -1.0], true),
                (Some([-4.0, 2.0, 1.0]), [0.9, -0.4, -0.2], true),
                (Some([-4.0, 2.0, 1.0]), [0.0, -0.1, -1.0], false),
                (None, [0.0, -0.1, -1.0], true),
            ] {
                let d = crate::mesh::normalize(view);
                let mid = path.between(0, 0.5);
                let picked = object_view(&mid, mesh.face_planes(), eye, d);
                assert_eq!(picked.is_some(), fast, "{eye:?} {view:?}");
                let model = |planes| {
                    let m = CoverageModel::new(
                        mesh.vertices(),
                        Some(rim(planes)),
                        path,
                        Filter::Box,
                        view,
                        eye,
                    );
                    format!("{m:?}")
                };
                let planes = mesh.face_planes();
                assert_eq!(model(Some(planes)), model(None), "{eye:?}");
            }
        }
    }
}
