//! Motion volumes of objects that spin but barely move (Wloka and Zeleznik, end of section 4.3).
//!
//! The paper: "Instead of using the motion vector to define the contour edges, we use the axis
//! of rotation. Similarly, we make the transparency proportional to the rotational speed."
//! Our construction of that sentence:
//!
//! - the object spins by `angle` radians (right hand about the unit `axis`, through `center`)
//!   and translates by `translation` over the shutter; the given vertices are its placement at
//!   shutter open;
//! - the contour comes from the rotation axis: each face's motion direction is the rotation
//!   about the axis at its centroid, `axis x (centroid - center)` (not one motion vector for the
//!   whole object, which a spin in place does not have). A face is front when
//!   `n . (axis x (centroid - center)) >= 0` (it turns towards the rotation), else back; the
//!   rotation keeps this split at every time. For a blade this makes the rim of its trailing
//!   side the contour: swept, its long edges give the sectors in the blade's planes and its tip
//!   edge the band at the tip radius, so the volume is the solid swept sector, seen correctly
//!   along the axis and from the side. Faces parallel to the rotation (a hub, a blade's flat
//!   sides) are front;
//! - the leading surface is the front faces at shutter close, the trailing surface the back
//!   faces at open, and the contour is swept around the axis through the last
//!   `min(|angle|, 2 pi)` radians of the spin (a sweep of more than one turn covers the same
//!   region again) in rings at most `pi / 12` apart (or `segments` rings);
//! - transparency follows the rotational speed: a vertex at distance `r` from the axis gets
//!   `a(r) = theta(r) / (theta(r) + B(r) phi)`, where `theta(r)` is the angle the object covers
//!   on the circle of radius `r` (seen along the axis), `B(r)` the number of arcs it covers
//!   there and `phi` the swept angle. Each arc (a blade) draws its leading face (`theta` of the
//!   circle) and one swept sector (`phi`), so the drawn alpha integrates to `theta(r)`, which
//!   is the time-averaged coverage of that circle: the total coverage is kept, and
//!   `a ~ theta / (B phi)` falls as the object spins faster. Where the object covers the whole
//!   circle (a hub) `a = 1`. Where the sectors overlap (`k = B phi / 2 pi > 1` layers), the
//!   layer alpha is `1 - (1 - k a)^(1/k)` so that the `k` layers composite to `k a`. `theta`
//!   and `B` come from a polar grid (128 radii, 720 angles) of the faces facing the axis,
//!   projected along it. A coarse mesh is cut (edges at most 1/12 of the radius) so that alphas
//!   can follow `theta(r) ~ 1 / r`;
//! - with a camera, alpha moves towards opaque as the view turns to side-on (the sectors are
//!   then edge-on and the object's faces carry the image): `1 - f (1 - a)` with
//!   `f = min(1, 2 |cos(view, axis)|)`. The camera does not select a contour line here (every
//!   contour edge is swept) and the section 4.1 normal rule is not applied;
//! - the shutter filter weights the rings: alpha `a(r) w(t_i)` with `w` the filter's density
//!   (unit mean) at the ring's shutter time, clamped to 1; for a spin of more than one turn the
//!   rings do not map to one time and the weight is 1.
use rayon::prelude::*;

use super::assemble::{assemble, AlphaMode, Sweep};
use super::build::motion_volume;
use super::filter::Filter;
use super::polar::{polar_occupancy, ANGLES, RADII};
use super::select::select_contour;
use super::subdivide::{subdivided, subdivision_for_edge};
use super::types::{check_options, check_segments, MotionVolume, VolumeOptions};
use crate::contour::contour_from_sides;
use crate::error::check_vector;
use crate::error::{Error, Result};
use crate::mesh::{dot, face_normal, normalize, Mesh};
use crate::motion::{Keyframe, Path};

const TAU: f64 = std::f64::consts::TAU;

/// A spin over the shutter.
#[derive(Debug, Clone, Copy)]
pub struct Spin {
    /// The rotation axis (any non-zero length).
    pub axis: [f64; 3],
    /// Radians over the shutter, right hand about `axis`.
    pub angle: f64,
    /// A point on the axis (world units).
    pub center: [f64; 3],
    /// Translation over the shutter (world units).
    pub translation: [f64; 3],
    /// Number of rings minus one; `None`: one per `pi / 12` of sweep.
    pub segments: Option<usize>,
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The keyframe rotating by `beta` about unit `w` through `c`, then translating by `t`.
fn rotation(w: [f64; 3], beta: f64, c: [f64; 3], t: [f64; 3]) -> Keyframe {
    let m = glam::DMat3::from_axis_angle(glam::DVec3::from_array(w), beta);
    let linear = m.transpose().to_cols_array_2d();
    let rc = m.mul_vec3(glam::DVec3::from_array(c)).to_array();
    Keyframe {
        linear,
        translation: [
            c[0] - rc[0] + t[0],
            c[1] - rc[1] + t[1],
            c[2] - rc[2] + t[2],
        ],
    }
}

/// The spin volume of `mesh` (see the module docs). Colours, normals and the camera rules are
/// those of [`motion_volume`].
pub fn spin_volume(mesh: &Mesh, spin: &Spin, opts: &VolumeOptions) -> Result<MotionVolume> {
    check_options(mesh, opts)?;
    let w = checked_axis(spin)?;
    let sweep = spin.angle.abs().min(TAU);
    let n = match spin.segments {
        Some(s) => {
            check_segments(s)?;
            s
        }
        None => ((sweep / (std::f64::consts::PI / 12.0)).ceil() as usize).max(1),
    };
    let path = Path::from_frames(&spin_frames(spin, w, sweep, n))?;
    if sweep == 0.0 {
        // No spin: the paper's motion volume of the translation (the mesh itself if none).
        return motion_volume(mesh, &path, opts);
    }
    let front = turning_faces(mesh, w, spin.center);
    let facing_axis: Vec<bool> = mesh
        .face_normals_raw()
        .par_iter()
        .map(|n| dot(*n, w) > 0.0)
        .collect();
    let (rmax, bins) = polar_occupancy(mesh, &facing_axis, spin.center, w);
    let dr = rmax / RADII as f64;
    let a_bin = bin_alphas(&bins, sweep);
    let along_view = view_factor(opts, spin.center, w);
    let axis_alpha = |p: &[f64; 3]| radial_alpha(p, spin.center, w, dr, &a_bin);
    // A coarse mesh (a box blade) is cut so that alphas can follow theta(r) ~ 1 / r.
    let parts = subdivision_for_edge(mesh, &path, rmax / 12.0);
    let sub = (parts > 1)
        .then(|| subdivided(mesh, opts, parts))
        .transpose()?;
    let (mesh, opts, front) = match &sub {
        Some((m, o, parent)) => (
            m,
            o,
            parent.par_iter().map(|&p| front[p as usize]).collect(),
        ),
        None => (mesh, opts, front),
    };
    let per_vertex: Vec<f64> = mesh
        .vertices()
        .par_iter()
        .map(|p| 1.0 - along_view * (1.0 - axis_alpha(p)))
        .collect();
    let weights: Vec<f64> = (0..=n)
        .map(|i| {
            if spin.angle.abs() > TAU {
                1.0
            } else {
                filter_density(opts.filter, i as f64 / n as f64)
            }
        })
        .collect();
    // Every contour edge is swept: the contour-line test of section 3.2 judges a swept sector by
    // the faces at its ends, which for a turning object drops sectors that are in view.
    let (contour, vis) = select_contour(mesh, contour_from_sides(mesh, &front), &front, None, None);
    let sweep = Sweep {
        mesh,
        path: &path,
        front: &front,
        contour: &contour,
        edge_visibility: &vis,
    };
    let alpha = AlphaMode::PerVertex(per_vertex, weights);
    assemble(sweep, false, &alpha, opts, None)
}

/// The spin's unit axis, every input checked first (errors name `axis`, `center`,
/// `translation` or `angle`).
fn checked_axis(spin: &Spin) -> Result<[f64; 3]> {
    check_vector(spin.axis, "axis")?;
    check_vector(spin.center, "center")?;
    check_vector(spin.translation, "translation")?;
    if !spin.angle.is_finite() {
        return Err(Error::value("angle", "is NaN or inf"));
    }
    let w = normalize(spin.axis);
    if w == [0.0; 3] {
        return Err(Error::value("axis", "is zero; a spin needs an axis"));
    }
    Ok(w)
}

/// `n + 1` keyframes of the spin about unit axis `w`: the last `sweep` radians of the turn
/// (at most a full turn), ending at `spin.angle`, with the translation in proportion.
fn spin_frames(spin: &Spin, w: [f64; 3], sweep: f64, n: usize) -> Vec<Keyframe> {
    let sign = if spin.angle < 0.0 { -1.0 } else { 1.0 };
    let start = spin.angle - sign * sweep;
    let t = spin.translation;
    (0..=n)
        .map(|i| {
            let u = i as f64 / n as f64;
            rotation(
                w,
                start + sign * sweep * u,
                spin.center,
                [t[0] * u, t[1] * u, t[2] * u],
            )
        })
        .collect()
}

/// Each radial bin's layer alpha from its `(theta, arcs)` occupancy (`polar_occupancy`) under a
/// turn of `sweep` radians: 1 for a full ring, 0 for an empty bin, else the coverage of the
/// sectors, with overlapping sectors (k = B phi / 2 pi layers on average) given the alpha at
/// which k layers composite to k times the linear one.
fn bin_alphas(bins: &[(f64, usize)], sweep: f64) -> Vec<f64> {
    bins.iter()
        .map(|&(theta, arcs)| {
            if theta >= TAU * (1.0 - 0.5 / ANGLES as f64) {
                1.0
            } else if arcs == 0 {
                0.0
            } else {
                let linear = theta / (theta + arcs as f64 * sweep);
                let k = (arcs as f64 * sweep / TAU).max(1.0);
                1.0 - (1.0 - (k * linear).min(1.0)).powf(1.0 / k)
            }
        })
        .collect()
}

/// How much of the sectors' transparency shows: seen from the side the sectors are edge-on and
/// the object's own faces carry the image, so with a camera the factor falls linearly to 0
/// (opaque) as the view turns from 60 degrees off the axis `w` to side-on (`min(1, 2 |cos|)`
/// of the angle between view and axis); 1 without a camera.
fn view_factor(opts: &VolumeOptions, center: [f64; 3], w: [f64; 3]) -> f64 {
    opts.camera.map_or(1.0, |eye| {
        let d = normalize([center[0] - eye[0], center[1] - eye[1], center[2] - eye[2]]);
        (2.0 * dot(d, w).abs()).min(1.0)
    })
}

/// The layer alpha at point `p` from the bins' alphas by its distance from the axis (`w`
/// through `center`; bins `dr` wide): linear between bin centres, and next to an empty bin
/// (a rim) the covered one's. 1 when the bins have no width.
fn radial_alpha(p: &[f64; 3], center: [f64; 3], w: [f64; 3], dr: f64, a_bin: &[f64]) -> f64 {
    if dr <= 0.0 {
        return 1.0;
    }
    let d = [p[0] - center[0], p[1] - center[1], p[2] - center[2]];
    let along = dot(d, w);
    let r = (dot(d, d) - along * along).max(0.0).sqrt();
    let g = (r / dr - 0.5).clamp(0.0, (RADII - 1) as f64);
    let k = (g.floor() as usize).min(RADII - 2);
    let (a0, a1) = (a_bin[k], a_bin[k + 1]);
    let (a0, a1) = (
        if a0 > 0.0 { a0 } else { a1 },
        if a1 > 0.0 { a1 } else { a0 },
    );
    a0 + (a1 - a0) * (g - k as f64)
}

/// Front (`true`) per face: its raw normal has `n . (w x (centroid - c)) >= 0`.
fn turning_faces(mesh: &Mesh, w: [f64; 3], c: [f64; 3]) -> Vec<bool> {
    let v = mesh.vertices();
    mesh.faces()
        .par_iter()
        .with_min_len(4096)
        .map(|f| {
            let (a, b, d) = (v[f[0] as usize], v[f[1] as usize], v[f[2] as usize]);
            let g = [
                (a[0] + b[0] + d[0]) / 3.0 - c[0],
                (a[1] + b[1] + d[1]) / 3.0 - c[1],
                (a[2] + b[2] + d[2]) / 3.0 - c[2],
            ];
            dot(face_normal(v, f), cross(w, g)) >= 0.0
        })
        .collect()
}

/// The filter's density `w(t)` (unit integral over [0, 1]).
fn filter_density(f: Filter, t: f64) -> f64 {
    let h = 1e-6;
    let (a, b) = ((t - h).max(0.0), (t + h).min(1.0));
    (f.cumulative_exact(b) - f.cumulative_exact(a)) / (b - a)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_keyframe_keeps_the_axis_and_centre() {
        let k = rotation([0.0, 0.0, 1.0], 0.7, [1.0, 2.0, 0.0], [0.0; 3]);
        let p = k.point([1.0, 2.0, 5.0]);
        assert!(
            (p[0] - 1.0).abs() < 1e-12 && (p[1] - 2.0).abs() < 1e-12 && (p[2] - 5.0).abs() < 1e-12
        );
        let q = k.point([2.0, 2.0, 0.0]);
        assert!(
            (q[0] - (1.0 + 0.7f64.cos())).abs() < 1e-12
                && (q[1] - (2.0 + 0.7f64.sin())).abs() < 1e-12
        );
    }

    #[test]
    fn a_full_disk_is_opaque_and_a_blade_is_a_fraction() {
        // A flat square [0.2, 1] x [-0.1, 0.1] facing +z: at radius ~0.6 it covers ~0.2/0.6 rad.
        let v = vec![
            [0.2, -0.1, 0.0],
            [1.0, -0.1, 0.0],
            [1.0, 0.1, 0.0],
            [0.2, 0.1, 0.0],
        ];
        let f = vec![[0, 1, 2], [0, 2, 3]];
        let mesh = Mesh::new(v, f).unwrap();
        let (rmax, bins) = polar_occupancy(&mesh, &[true, true], [0.0; 3], [0.0, 0.0, 1.0]);
        let k = ((0.6 / rmax) * RADII as f64) as usize;
        let (theta, arcs) = bins[k];
        assert_eq!(arcs, 1);
        assert!(
            (theta - 2.0 * (0.1f64 / 0.6).asin()).abs() < 0.03,
            "{theta}"
        );
        assert!(filter_density(Filter::Box, 0.3) - 1.0 < 1e-9);
        assert!((filter_density(Filter::Triangle, 0.5) - 2.0).abs() < 1e-5);
    }
}
