//! The occupancy of a spinning object seen along its axis, on a polar grid (for the alphas of
//! `spin.rs`): per radius, the angle the object covers on that circle and the number of arcs
//! (blades) it covers there.
use rayon::prelude::*;

use crate::mesh::{dot, normalize, Mesh};

/// Radial bins of the grid.
pub(super) const RADII: usize = 128;
/// Angle cells of the grid.
pub(super) const ANGLES: usize = 720;
const TAU: f64 = std::f64::consts::TAU;

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Per radial bin: (angle covered, number of covered arcs) of the faces flagged in `front`
/// (those facing the axis, which tile the object's projection along it) seen along `w`.
///
/// The grid's cell `(k, a)` is the point at radius `(k + 1/2) dr` and angle `(a + 1/2) 2 pi /
/// ANGLES`, hit when a triangle holds it ([`Polar::holds`]). Each triangle tests only the cells
/// of its own ring of radii and wedge of angles ([`Polar::cells`], widened by a cell on each
/// side against rounding), so the work is the triangles' area in cells, not every triangle
/// times every cell; the hits are those of testing every cell.
pub(super) fn polar_occupancy(
    mesh: &Mesh,
    front: &[bool],
    c: [f64; 3],
    w: [f64; 3],
) -> (f64, Vec<(f64, usize)>) {
    let helper = if w[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let e1 = normalize(cross(helper, w));
    let e2 = cross(w, e1);
    let v = mesh.vertices();
    let flat: Vec<[f64; 2]> = v
        .par_iter()
        .map(|p| {
            let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
            [dot(d, e1), dot(d, e2)]
        })
        .collect();
    let rmax = flat
        .iter()
        .map(|p| (p[0] * p[0] + p[1] * p[1]).sqrt())
        .fold(0.0, f64::max);
    if rmax <= 0.0 {
        return (0.0, vec![(TAU, 1); RADII]);
    }
    let dr = rmax / RADII as f64;
    let tris: Vec<Polar> = mesh
        .faces()
        .iter()
        .zip(front)
        .filter(|(_, &f)| f)
        .filter_map(|(f, _)| Polar::new(f.map(|i| flat[i as usize]), dr))
        .collect();
    // Triangles by radial bin (each listed in every bin of its ring).
    let mut by_ring: Vec<Vec<u32>> = vec![Vec::new(); RADII];
    for (i, t) in tris.iter().enumerate() {
        for list in &mut by_ring[t.rings.0..=t.rings.1] {
            list.push(i as u32);
        }
    }
    let bins: Vec<(f64, usize)> = by_ring
        .par_iter()
        .enumerate()
        .map(|(k, list)| {
            let r = (k as f64 + 0.5) * dr;
            let mut hit = vec![false; ANGLES];
            for &i in list {
                let t = &tris[i as usize];
                for a in t.cells() {
                    if !hit[a] {
                        let ang = (a as f64 + 0.5) * TAU / ANGLES as f64;
                        hit[a] = t.holds([r * ang.cos(), r * ang.sin()]);
                    }
                }
            }
            let count = hit.iter().filter(|h| **h).count();
            let arcs = (0..ANGLES)
                .filter(|&a| hit[a] && !hit[(a + ANGLES - 1) % ANGLES])
                .count();
            (count as f64 * TAU / ANGLES as f64, arcs)
        })
        .collect();
    (rmax, bins)
}

/// A projected triangle of [`polar_occupancy`], with the radial bins and the angle cells that
/// can hold its points.
struct Polar {
    t: [[f64; 2]; 3],
    area2: f64,
    /// First and last radial bin (inclusive).
    rings: (usize, usize),
    /// First angle cell and the number of cells (all of them around the centre).
    wedge: (usize, usize),
}

impl Polar {
    /// `None` for a degenerate triangle (it holds no point).
    fn new(t: [[f64; 2]; 3], dr: f64) -> Option<Self> {
        let area2 =
            (t[1][0] - t[0][0]) * (t[2][1] - t[0][1]) - (t[1][1] - t[0][1]) * (t[2][0] - t[0][0]);
        if area2 == 0.0 {
            return None;
        }
        let mut p = Polar {
            t,
            area2,
            rings: (0, 0),
            wedge: (0, ANGLES),
        };
        let radius = |q: [f64; 2]| (q[0] * q[0] + q[1] * q[1]).sqrt();
        let hi = t.iter().map(|&q| radius(q)).fold(0.0, f64::max);
        // The distance from the centre to the triangle: 0 when it holds the centre, else to
        // its nearest edge.
        let lo = if p.holds([0.0, 0.0]) {
            0.0
        } else {
            (0..3)
                .map(|i| {
                    let (a, b) = (t[i], t[(i + 1) % 3]);
                    let e = [b[0] - a[0], b[1] - a[1]];
                    let ee = e[0] * e[0] + e[1] * e[1];
                    let s = if ee > 0.0 {
                        (-(a[0] * e[0] + a[1] * e[1]) / ee).clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                    radius([a[0] + s * e[0], a[1] + s * e[1]])
                })
                .fold(f64::INFINITY, f64::min)
        };
        // Bin k's radius (k + 1/2) dr within [lo, hi], a bin more on each side.
        let last = (RADII - 1) as f64;
        let k0 = ((lo / dr - 0.5).ceil() - 1.0).clamp(0.0, last) as usize;
        let k1 = ((hi / dr - 0.5).floor() + 1.0).clamp(0.0, last) as usize;
        p.rings = (k0, k1.max(k0));
        // Away from the centre (at least a hundredth of its farthest corner) the triangle lies in
        // a wedge narrower than a half turn, spanned by its corners' angles.
        if lo > 1e-2 * hi {
            let ang = t.map(|q| q[1].atan2(q[0]));
            let wrap = |x: f64| {
                let y = x.rem_euclid(TAU);
                if y > std::f64::consts::PI {
                    y - TAU
                } else {
                    y
                }
            };
            let off = ang.map(|a| wrap(a - ang[0]));
            let (a_lo, a_hi) = off
                .iter()
                .fold((0.0f64, 0.0f64), |(l, h), &x| (l.min(x), h.max(x)));
            // Cell a's angle (a + 1/2) 2 pi / ANGLES within [ang0 + a_lo, ang0 + a_hi], a cell
            // more on each side.
            let cell = TAU / ANGLES as f64;
            let first = ((ang[0] + a_lo) / cell - 0.5).ceil() - 1.0;
            let last = ((ang[0] + a_hi) / cell - 0.5).floor() + 1.0;
            let count = (last - first + 1.0).max(0.0) as usize;
            if count < ANGLES {
                p.wedge = ((first as i64).rem_euclid(ANGLES as i64) as usize, count);
            }
        }
        Some(p)
    }

    /// The angle cells to test, in order around the circle from the wedge's first.
    fn cells(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.wedge.1).map(move |i| (self.wedge.0 + i) % ANGLES)
    }

    /// Whether the triangle holds `q` (on its edges included).
    fn holds(&self, q: [f64; 2]) -> bool {
        let t = &self.t;
        let s = |a: [f64; 2], b: [f64; 2]| {
            (b[0] - a[0]) * (q[1] - a[1]) - (b[1] - a[1]) * (q[0] - a[0])
        };
        let (x, y, z) = (s(t[0], t[1]), s(t[1], t[2]), s(t[2], t[0]));
        if self.area2 > 0.0 {
            x >= 0.0 && y >= 0.0 && z >= 0.0
        } else {
            x <= 0.0 && y <= 0.0 && z <= 0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every cell of the grid tested against every triangle (the occupancy's definition).
    fn occupancy_of_every_cell(tris: &[Polar], dr: f64) -> Vec<(f64, usize)> {
        (0..RADII)
            .map(|k| {
                let r = (k as f64 + 0.5) * dr;
                let hit: Vec<bool> = (0..ANGLES)
                    .map(|a| {
                        let ang = (a as f64 + 0.5) * TAU / ANGLES as f64;
                        tris.iter().any(|t| t.holds([r * ang.cos(), r * ang.sin()]))
                    })
                    .collect();
                let count = hit.iter().filter(|h| **h).count();
                let arcs = (0..ANGLES)
                    .filter(|&a| hit[a] && !hit[(a + ANGLES - 1) % ANGLES])
                    .count();
                (count as f64 * TAU / ANGLES as f64, arcs)
            })
            .collect()
    }

    #[test]
    fn occupancy_equals_testing_every_cell() {
        // A sphere off the axis (its faces at every angle and radius, some round the centre),
        // and a blade through the centre, seen along tilted axes.
        let (v, f) = crate::mesh::uv_sphere(9, 17);
        let off: Vec<[f64; 3]> = v.iter().map(|p| [p[0] + 0.4, p[1] - 0.2, p[2]]).collect();
        for (verts, axis) in [
            (off, [0.1, 0.2, 1.0]),
            (v.clone(), [0.0, 0.0, 1.0]),
            (
                v.iter()
                    .map(|p| [p[0] * 3.0, p[1] * 0.05, p[2] * 0.3])
                    .collect(),
                [0.3, -0.1, 1.0],
            ),
        ] {
            let mesh = Mesh::new(verts, f.clone()).unwrap();
            let w = normalize(axis);
            let front: Vec<bool> = mesh
                .face_normals_raw()
                .iter()
                .map(|n| dot(*n, w) > 0.0)
                .collect();
            let (rmax, bins) = polar_occupancy(&mesh, &front, [0.0; 3], w);
            // The same projection as the kernel's, every front face.
            let helper = if w[0].abs() < 0.9 {
                [1.0, 0.0, 0.0]
            } else {
                [0.0, 1.0, 0.0]
            };
            let e1 = normalize(cross(helper, w));
            let e2 = cross(w, e1);
            let flat: Vec<[f64; 2]> = mesh
                .vertices()
                .iter()
                .map(|p| [dot(*p, e1), dot(*p, e2)])
                .collect();
            let dr = rmax / RADII as f64;
            let tris: Vec<Polar> = mesh
                .faces()
                .iter()
                .zip(&front)
                .filter(|(_, &fr)| fr)
                .filter_map(|(t, _)| Polar::new(t.map(|i| flat[i as usize]), dr))
                .collect();
            assert!(tris.iter().any(|t| t.wedge.1 < ANGLES / 4));
            assert_eq!(bins, occupancy_of_every_cell(&tris, dr));
        }
    }
}
