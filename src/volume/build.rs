//! The construction of a motion volume: the face split, the contour and the alphas, handed
//! to the assembly.
use rayon::prelude::*;

use super::assemble::{assemble, AlphaMode, Seen, Sweep};
use super::coverage::{default_view, CoverageModel};
use super::filter::Filter;
use super::rim::Rim;
use super::select::select_contour;
use super::subdivide::{subdivided, subdivision_factor};
use super::types::{check_options, check_segments, Colors, MotionVolume, VolumeOptions, LEADING};
use crate::contour::{classify_faces, classify_faces_seen, contour_from_sides};
use crate::error::Result;
use crate::mesh::{dot, normalize, Mesh};
use crate::motion::{Keyframe, Path};

/// Above this many vertices the coverage model takes its hulls over the mesh's rim (when the
/// mesh is closed), not over every projected vertex.
const RIM_VERTICES: usize = 4096;

/// The view direction of the coverage model: from the camera to the centroid at mid-shutter
/// (for a translation, made perpendicular to the motion unless within 37 degrees of it, see
/// `coverage.rs`), else [`default_view`] of the summed motion.
fn view_direction(
    path: &Path,
    centroid: [f64; 3],
    total: [f64; 3],
    camera: Option<[f64; 3]>,
) -> [f64; 3] {
    if let Some(eye) = camera {
        let c = path.at(0.5).point(centroid);
        let d = normalize([c[0] - eye[0], c[1] - eye[1], c[2] - eye[2]]);
        if d != [0.0; 3] {
            // A translation seen on a picture plane parallel to the motion moves every image
            // point along parallel lines (its vanishing point at infinity), as the model's
            // translated hull assumes; on the camera's own plane they converge.
            let m = normalize(total);
            let c = dot(d, m);
            if path.is_translation() && m != [0.0; 3] && c.abs() < 0.8 {
                return normalize([d[0] - c * m[0], d[1] - c * m[1], d[2] - c * m[2]]);
            }
            return d;
        }
    }
    default_view(total)
}

fn mean(vertices: &[[f64; 3]]) -> [f64; 3] {
    let s = vertices
        .iter()
        .fold([0.0; 3], |a, v| [a[0] + v[0], a[1] + v[1], a[2] + v[2]]);
    let k = vertices.len() as f64;
    [s[0] / k, s[1] / k, s[2] / k]
}

/// A subdivided mesh, its options and each new face's parent face (`subdivided`).
type Subdivided = (Mesh, VolumeOptions, Vec<u32>);

/// The volume of a path that does not move: the mesh placed at the keyframe, all leading and
/// opaque (with per-face colours, through `assemble`).
fn static_volume(mesh: &Mesh, path: &Path, opts: &VolumeOptions) -> Result<MotionVolume> {
    let n = path.segments();
    let verts = mesh.vertices();
    let face_colors = matches!(opts.colors, Colors::PerFace(_));
    if face_colors {
        let front = vec![true; mesh.faces().len()];
        let alpha = AlphaMode::Rings(vec![1.0; n + 1]);
        let sweep = Sweep {
            mesh,
            path,
            front: &front,
            contour: &[],
            edge_visibility: &[],
        };
        return assemble(sweep, false, &alpha, opts, None);
    }
    // The mesh itself (every vertex, in order), placed by T_0, all leading and opaque.
    let f0 = &path.frames[0];
    let c = |v: usize| match &opts.colors {
        Colors::PerVertex(c) => c[v],
        Colors::Uniform(c) => *c,
        // Not reached: per-face colours take the assemble path above.
        Colors::PerFace(c) => c.first().copied().unwrap_or([1.0; 4]),
    };
    let obj_normals = opts
        .normals
        .as_deref()
        .unwrap_or_else(|| mesh.cached_vertex_normals());
    Ok(MotionVolume {
        vertices: verts.par_iter().map(|v| f0.point(*v)).collect(),
        faces: mesh.faces().to_vec(),
        rgba: (0..verts.len()).map(c).collect(),
        normals: obj_normals
            .iter()
            .map(|n| {
                let w = normalize(f0.normal(*n));
                [w[0] as f32, w[1] as f32, w[2] as f32]
            })
            .collect(),
        part: vec![LEADING; mesh.faces().len()],
        ring_alpha: vec![1.0; n + 1],
        contour_edges: 0,
        contour_error: 0.0,
    })
}

/// The filter opacities of the volume of `mesh` moving along `path` (its centroid by `total`
/// over the shutter): the ramp's ring alphas, or the coverage model of the other filters with
/// the mesh subdivided where its faces are too large for the model's knots.
fn alpha_mode(
    mesh: &Mesh,
    path: &Path,
    opts: &VolumeOptions,
    centroid: [f64; 3],
    total: [f64; 3],
) -> Result<(AlphaMode, Option<Subdivided>)> {
    let verts = mesh.vertices();
    let lengths: Vec<f64> = path
        .segment_vectors(centroid)
        .into_iter()
        .map(|s| dot(s, s).sqrt())
        .collect();
    let extent = extent_along(mesh, path, total);
    Ok(match opts.filter {
        Filter::Ramp => (
            AlphaMode::Rings(Filter::Ramp.ring_alphas(&lengths, extent)),
            None,
        ),
        f => {
            let view = view_direction(path, centroid, total, opts.camera);
            // The rim pays off once projecting and sorting every vertex costs more than the
            // per-face orientations.
            let rim = (verts.len() > RIM_VERTICES)
                .then(|| mesh.face_neighbors())
                .flatten()
                .map(|neighbors| Rim {
                    faces: mesh.faces(),
                    neighbors,
                    planes: Some(mesh.face_planes()),
                });
            let model =
                CoverageModel::new(verts, rim, path, f, view, opts.camera).windowed(opts.window);
            let s = subdivision_factor(mesh, path, lengths.iter().sum(), extent);
            let sub = (s > 1).then(|| subdivided(mesh, opts, s)).transpose()?;
            (
                AlphaMode::Coverage(Box::new(model), f.knots_per_segment()),
                sub,
            )
        }
    })
}

/// Build the motion volume of `mesh` moving along `path` (already subdivided).
pub fn motion_volume(mesh: &Mesh, path: &Path, opts: &VolumeOptions) -> Result<MotionVolume> {
    check_options(mesh, opts)?;
    let n = path.segments();
    check_segments(n)?;
    if path.is_static() {
        return static_volume(mesh, path, opts);
    }
    let verts = mesh.vertices();
    // Motion vector, extent, ring opacities.
    let centroid = mean(verts);
    let (first, last) = (&path.frames[0], &path.frames[n]);
    let total = if path.is_translation() {
        let (p, q) = (first.translation, last.translation);
        [q[0] - p[0], q[1] - p[1], q[2] - p[2]]
    } else {
        let (p, q) = (first.point(centroid), last.point(centroid));
        [q[0] - p[0], q[1] - p[1], q[2] - p[2]]
    };
    let m_obj = last.inverse_vector(total);
    let (alpha, sub) = alpha_mode(mesh, path, opts, centroid, total)?;
    // A subdivided face takes the sides of its parent face: the split of a face parallel to
    // the motion (n . m = 0) must not depend on the rounding of the new vertices.
    let line_eye = opts.camera.filter(|_| opts.contour_line);
    // Section 4.4: the split and contour of the stored direction nearest the motion (none for a
    // motion that ends where it started: no direction).
    let stored = match &opts.contours {
        Some(table) if m_obj != [0.0; 3] => Some(table.lookup(mesh, m_obj)?),
        _ => None,
    };
    let (front, vis) = match (line_eye, stored, opts.contours.as_deref()) {
        (Some(eye), Some((set, _)), Some(table)) => (
            set.front.clone(),
            Some(table.faces_seen(mesh, eye, last, first)),
        ),
        (Some(eye), _, _) => {
            let (f, lead, trail) = classify_faces_seen(mesh, m_obj, eye, last, first);
            (f, Some((lead, trail)))
        }
        (None, Some((set, _)), _) => (set.front.clone(), None),
        (None, None, _) => (classify_faces(mesh, m_obj), None),
    };
    let (mesh, opts, front, vis) = match &sub {
        Some((m, o, parent)) => {
            let map = |x: &[bool]| {
                parent
                    .par_iter()
                    .map(|&p| x[p as usize])
                    .collect::<Vec<bool>>()
            };
            (m, o, map(&front), vis.map(|(l, t)| (map(&l), map(&t))))
        }
        None => (mesh, opts, front, vis),
    };
    // The stored contour, unless the mesh was subdivided (its split maps to the new faces).
    let contour = match (stored, &sub) {
        (Some((set, _)), None) => set.contour.clone(),
        _ => contour_from_sides(mesh, &front),
    };
    // A path that turns keeps the strips facing the camera (see `select_contour`), unless it
    // turns more than it moves: then the split of the centroid's motion is arbitrary, and the
    // strips of an arbitrary contour facing the camera cover the image twice (a propeller's
    // pieces of shutter: +12% coverage with them, +3% without).
    let strips = line_eye
        .filter(|_| !path.is_translation() && !turns_in_place(verts, first, last, total))
        .map(|eye| (path, eye));
    let (contour, edge_vis) = select_contour(mesh, contour, &front, vis.as_ref(), strips);
    let seen = vis.as_ref().map(|(lead, trail)| Seen {
        lead,
        trail,
        only: opts.visible_only,
    });
    let sweep = Sweep {
        mesh,
        path,
        front: &front,
        contour: &contour,
        edge_visibility: &edge_vis,
    };
    let mut vol = assemble(sweep, line_eye.is_some(), &alpha, opts, seen)?;
    vol.contour_error = stored.map_or(0.0, |(_, angle)| angle);
    Ok(vol)
}

/// Whether some vertex moves from `first` to `last` by more than twice the centroid's motion
/// `total` beyond that motion (the path turns more than it moves).
fn turns_in_place(verts: &[[f64; 3]], first: &Keyframe, last: &Keyframe, total: [f64; 3]) -> bool {
    let limit = 4.0 * dot(total, total);
    verts.par_iter().any(|v| {
        let (p, q) = (first.point(*v), last.point(*v));
        let d = [
            q[0] - p[0] - total[0],
            q[1] - p[1] - total[1],
            q[2] - p[2] - total[2],
        ];
        dot(d, d) > limit
    })
}

/// The extent of the mesh placed at shutter close along the summed motion `total` (0 if none).
fn extent_along(mesh: &Mesh, path: &Path, total: [f64; 3]) -> f64 {
    let dir = normalize(total);
    if dir == [0.0; 3] {
        return 0.0;
    }
    // (L_n v) . d = v . (L_n^T d); the translation cancels in max - min.
    let last = &path.frames[path.segments()];
    let d_obj = last
        .mat3()
        .transpose()
        .mul_vec3(glam::DVec3::from_array(dir))
        .to_array();
    let (lo, hi) = mesh
        .vertices()
        .par_iter()
        .map(|v| {
            let x = dot(*v, d_obj);
            (x, x)
        })
        .reduce(
            || (f64::INFINITY, f64::NEG_INFINITY),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );
    hi - lo
}
