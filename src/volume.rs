//! Motion volumes (Wloka and Zeleznik, sections 3.3-3.4 and 4.1-4.3).
//!
//! For keyframes `T_0 .. T_n` (shutter open to close, see [`crate::motion`]) and the summed
//! motion vector `M` (displacement from `T_0` to `T_n`; for a translation path exactly the
//! difference of the translations), faces are split in object space into front (`n . m >= 0`,
//! `m = L_n^-1 M`) and back. The volume is:
//! - the *leading* surface: the front faces placed by `T_n` (shutter close), part 0;
//! - the *trailing* surface: the back faces placed by `T_0` (shutter open), part 1;
//! - the *joining* surface, part 2: for every contour edge `(a, b)` and segment `j`, the quad
//!   `a_{j-1} b_{j-1} b_j a_j` between the contour placed by `T_{j-1}` and by `T_j` (two
//!   triangles), so the contour is oriented at every keyframe time (section 4.3).
//!
//! Without a camera, joining vertices at the first and last ring are the trailing and leading
//! vertices themselves, so a closed, consistently wound mesh gives a closed, consistently wound
//! volume. With a camera, only the contour line is swept (edges with an adjacent face that faces
//! the camera: front faces placed at close, back faces at open) and every joining quad strip has
//! its own vertices, so that section 4.1's rule can apply per edge: when only the trailing
//! (leading) side is visible, all joining vertices of the edge take the trailing (leading)
//! normal. Colours are per mesh vertex, so leading and trailing colours of an edge agree.
//!
//! Normals are rotated by each ring's keyframe. Alpha comes from [`crate::volume_filter`] and
//! multiplies the colour's own (straight) alpha. If every keyframe is the same, the result is the
//! mesh itself placed by `T_0`, all leading and opaque (colour alpha only).
use rayon::prelude::*;

use crate::contour::{
    camera_facing, check_vector, classify_faces, contour_from_sides, contour_line, ContourEdge,
};
use crate::mesh::{dot, normalize, Mesh, MAX_ELEMENTS};
use crate::motion::Path;
use crate::volume_alpha::{default_view, subdivide, CoverageModel, Subdivision};
use crate::volume_filter::Filter;
use crate::{Error, Result};

pub const LEADING: u8 = 0;
pub const TRAILING: u8 = 1;
pub const JOINING: u8 = 2;

/// Largest number of segments accepted.
pub const MAX_SEGMENTS: usize = 4096;

/// Colours: one straight RGBA for all, one per mesh vertex, or one per mesh face.
///
/// With per-face colours every leading and trailing face has its own three vertices and every
/// joining strip its own vertices, coloured from the strip's front face (leading end) to its back
/// face (trailing end), or with the visible side's colour only when the camera sees one side
/// (section 4.1); the volume is then closed geometrically but not as an indexed mesh.
#[derive(Debug, Clone)]
pub enum Colors {
    Uniform([f32; 4]),
    PerVertex(Vec<[f32; 4]>),
    PerFace(Vec<[f32; 4]>),
}

/// Options of [`motion_volume`].
#[derive(Debug, Clone)]
pub struct VolumeOptions {
    pub filter: Filter,
    pub colors: Colors,
    /// Per-vertex normals in object space; `None`: area-weighted vertex normals.
    pub normals: Option<Vec<[f64; 3]>>,
    pub camera: Option<[f64; 3]>,
    /// With a camera: sweep only the contour line (section 3.2) and apply the section 4.1
    /// normal rule (`true`), or sweep every contour edge and use the camera for the coverage
    /// alphas only (`false`).
    pub contour_line: bool,
}

impl Default for VolumeOptions {
    fn default() -> Self {
        VolumeOptions {
            filter: Filter::Ramp,
            colors: Colors::Uniform([1.0; 4]),
            normals: None,
            camera: None,
            contour_line: true,
        }
    }
}

/// The assembled motion volume.
#[derive(Debug, Clone, PartialEq)]
pub struct MotionVolume {
    pub vertices: Vec<[f64; 3]>,
    pub faces: Vec<[u32; 3]>,
    /// Straight (non-premultiplied) linear RGBA per vertex.
    pub rgba: Vec<[f32; 4]>,
    /// Unit normals per vertex (zero where the mesh normal is undefined).
    pub normals: Vec<[f32; 3]>,
    /// `LEADING`, `TRAILING` or `JOINING` per face.
    pub part: Vec<u8>,
    /// Opacity of each contour ring, open (index 0) to close (index n).
    pub ring_alpha: Vec<f64>,
    /// Number of contour edges swept.
    pub contour_edges: usize,
}

/// Where an output vertex comes from: mesh vertex; placement at `frac` of the way from keyframe
/// `seg` to `seg + 1` (0: the keyframe itself); keyframe for its normal.
#[derive(Clone, Copy)]
struct Source {
    v: u32,
    seg: u32,
    frac: f64,
    normal_ring: u32,
    /// Per-face colours: the colour is `face_colors[back]` blended towards `face_colors[front]`
    /// by `towards_front`; `front == u32::MAX` for vertex colours.
    front: u32,
    back: u32,
    towards_front: f32,
}

pub(crate) fn check_options(mesh: &Mesh, opts: &VolumeOptions) -> Result<()> {
    let nv = mesh.vertices().len();
    let check_rgba = |c: &[f32; 4]| {
        c.iter().all(|x| x.is_finite())
            && c[..3].iter().all(|x| *x >= 0.0)
            && (0.0..=1.0).contains(&c[3])
    };
    match &opts.colors {
        Colors::Uniform(c) if !check_rgba(c) => {
            return Err(Error::value(
                "colors",
                "must be finite, RGB >= 0 and alpha in [0, 1]",
            ));
        }
        Colors::PerFace(c) => {
            let nf = mesh.faces().len();
            if c.len() != nf {
                return Err(Error::shape(
                    "face_colors",
                    format!("expected {nf} colours, got {}", c.len()),
                ));
            }
            if !c.par_iter().all(check_rgba) {
                return Err(Error::value(
                    "face_colors",
                    "must be finite, RGB >= 0 and alpha in [0, 1]",
                ));
            }
        }
        Colors::PerVertex(c) => {
            if c.len() != nv {
                return Err(Error::shape(
                    "colors",
                    format!("expected {nv} colours, got {}", c.len()),
                ));
            }
            if !c.par_iter().all(check_rgba) {
                return Err(Error::value(
                    "colors",
                    "must be finite, RGB >= 0 and alpha in [0, 1]",
                ));
            }
        }
        _ => {}
    }
    if let Some(n) = &opts.normals {
        if n.len() != nv {
            return Err(Error::shape(
                "normals",
                format!("expected {nv} normals, got {}", n.len()),
            ));
        }
        if !n.par_iter().all(|x| x.iter().all(|c| c.is_finite())) {
            return Err(Error::value("normals", "is NaN or inf"));
        }
    }
    if let Some(eye) = opts.camera {
        check_vector(eye, "camera_position")?;
    }
    Ok(())
}

/// How the vertices of a volume get their filter opacity.
pub(crate) enum AlphaMode {
    /// One opacity per keyframe ring (the paper's ramp); no extra cuts in the joining strips.
    Rings(Vec<f64>),
    /// The coverage model; every joining segment is cut at `q + 1` per-vertex times.
    Coverage(Box<CoverageModel>, usize),
    /// One opacity per mesh vertex times a weight per keyframe ring (see `crate::spin`).
    PerVertex(Vec<f64>, Vec<f64>),
}

/// The view direction of the coverage model: from the camera to the centroid at mid-shutter,
/// else [`default_view`] of the summed motion.
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

/// Build the motion volume of `mesh` moving along `path` (already subdivided).
pub fn motion_volume(mesh: &Mesh, path: &Path, opts: &VolumeOptions) -> Result<MotionVolume> {
    check_options(mesh, opts)?;
    let n = path.segments();
    if n == 0 || n > MAX_SEGMENTS {
        return Err(Error::value(
            "segments",
            format!("total segments must be in 1..={MAX_SEGMENTS}, got {n}"),
        ));
    }
    let verts = mesh.vertices();
    let face_colors = matches!(opts.colors, Colors::PerFace(_));
    if path.is_static() && face_colors {
        let front = vec![true; mesh.faces().len()];
        let alpha = AlphaMode::Rings(vec![1.0; n + 1]);
        return assemble(mesh, path, &front, &[], &[], false, &alpha, opts);
    }
    if path.is_static() {
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
            .clone()
            .unwrap_or_else(|| mesh.vertex_normals());
        return Ok(MotionVolume {
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
        });
    }
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
    let lengths: Vec<f64> = path
        .segment_vectors(centroid)
        .into_iter()
        .map(|s| dot(s, s).sqrt())
        .collect();
    let extent = extent_along(mesh, path, total);
    let (alpha, sub) = match opts.filter {
        Filter::Ramp => (
            AlphaMode::Rings(Filter::Ramp.ring_alphas(&lengths, extent)),
            None,
        ),
        f => {
            let view = view_direction(path, centroid, total, opts.camera);
            let model = CoverageModel::new(verts, path, f, view, opts.camera);
            let s = subdivision_factor(mesh, path, lengths.iter().sum(), extent);
            let sub = (s > 1).then(|| subdivided(mesh, opts, s)).transpose()?;
            (
                AlphaMode::Coverage(Box::new(model), f.knots_per_segment()),
                sub,
            )
        }
    };
    // A subdivided face takes the sides of its parent face: the split of a face parallel to
    // the motion (n . m = 0) must not depend on the rounding of the new vertices.
    let front = classify_faces(mesh, m_obj);
    let line_eye = opts.camera.filter(|_| opts.contour_line);
    let vis = line_eye.map(|eye| camera_sides(mesh, path, eye));
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
    let (contour, vis) = select_contour(mesh, &front, vis.as_ref());
    assemble(
        mesh,
        path,
        &front,
        &contour,
        &vis,
        line_eye.is_some(),
        &alpha,
        opts,
    )
}

/// Whether each face faces the camera at `eye` when placed at shutter close and at open.
pub(crate) fn camera_sides(mesh: &Mesh, path: &Path, eye: [f64; 3]) -> (Vec<bool>, Vec<bool>) {
    let (first, last) = (&path.frames[0], &path.frames[path.segments()]);
    (
        camera_facing(mesh, eye, |p| last.point(p)),
        camera_facing(mesh, eye, |p| first.point(p)),
    )
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

/// Largest number of faces a coverage-filter subdivision may produce.
const MAX_SUBDIVIDED_FACES: usize = 1 << 20;

/// How finely to cut a coarse mesh so that per-vertex coverage alphas can follow the coverage
/// profile along the motion, which changes over `min(path length, extent)`: every edge (world
/// units, at shutter open) is cut to at most `max(min(L, E) / 2, E / 8)`, in 1..=8 parts, and
/// the result stays under [`MAX_SUBDIVIDED_FACES`].
fn subdivision_factor(mesh: &Mesh, path: &Path, length: f64, extent: f64) -> usize {
    subdivision_for_edge(mesh, path, (0.25 * length.min(extent)).max(extent / 16.0))
}

/// The number of parts (1..=16, within [`MAX_SUBDIVIDED_FACES`]) that cuts every edge of the
/// mesh placed by the first keyframe to at most `h` (world units).
pub(crate) fn subdivision_for_edge(mesh: &Mesh, path: &Path, h: f64) -> usize {
    let faces = mesh.faces();
    if h.is_nan() || h <= 0.0 || faces.len() * 4 > MAX_SUBDIVIDED_FACES {
        return 1;
    }
    let v = mesh.vertices();
    let f0 = &path.frames[0];
    let longest = faces
        .par_iter()
        .map(|f| {
            (0..3)
                .map(|k| {
                    let (a, b) = (v[f[k] as usize], v[f[(k + 1) % 3] as usize]);
                    let d = f0.vector([b[0] - a[0], b[1] - a[1], b[2] - a[2]]);
                    dot(d, d).sqrt()
                })
                .fold(0.0, f64::max)
        })
        .reduce(|| 0.0, f64::max);
    let by_budget = ((MAX_SUBDIVIDED_FACES / faces.len()) as f64).sqrt().floor() as usize;
    ((longest / h).ceil() as usize)
        .clamp(1, 16)
        .min(by_budget.max(1))
}

/// The mesh cut `s` times along every edge, with colours and normals blended to the new vertices.
pub(crate) fn subdivided(
    mesh: &Mesh,
    opts: &VolumeOptions,
    s: usize,
) -> Result<(Mesh, VolumeOptions, Vec<u32>)> {
    let Subdivision {
        vertices: sv,
        faces: sf,
        blend,
        parent,
    } = subdivide(mesh.vertices(), mesh.faces(), s);
    let normals = opts
        .normals
        .clone()
        .unwrap_or_else(|| mesh.vertex_normals());
    let mix3 = |(ids, w): &([u32; 3], [f64; 3])| {
        let mut o = [0.0; 3];
        for (i, wi) in ids.iter().zip(w) {
            for (x, y) in o.iter_mut().zip(normals[*i as usize]) {
                *x += wi * y;
            }
        }
        o
    };
    let colors = match &opts.colors {
        Colors::Uniform(c) => Colors::Uniform(*c),
        Colors::PerFace(c) => Colors::PerFace(parent.iter().map(|&p| c[p as usize]).collect()),
        Colors::PerVertex(c) => Colors::PerVertex(
            blend
                .iter()
                .map(|(ids, w)| {
                    let mut o = [0.0f32; 4];
                    for (i, wi) in ids.iter().zip(w) {
                        for (x, y) in o.iter_mut().zip(c[*i as usize]) {
                            *x += *wi as f32 * y;
                        }
                    }
                    o
                })
                .collect(),
        ),
    };
    let out = VolumeOptions {
        filter: opts.filter,
        colors,
        normals: Some(blend.par_iter().map(mix3).collect()),
        camera: opts.camera,
        contour_line: opts.contour_line,
    };
    Ok((Mesh::new(sv, sf)?, out, parent))
}

/// The contour edges of a face split; with the camera sides of the faces (facing the camera at
/// close, at open), the contour line and, per edge, whether its leading (front faces at close)
/// and trailing (back faces at open) sides face the camera.
pub(crate) fn select_contour(
    mesh: &Mesh,
    front: &[bool],
    sides: Option<&(Vec<bool>, Vec<bool>)>,
) -> (Vec<ContourEdge>, Vec<(bool, bool)>) {
    let contour = contour_from_sides(mesh, front);
    let Some((vis_lead, vis_trail)) = sides else {
        return (contour, Vec::new());
    };
    let visible: Vec<bool> = (0..front.len())
        .into_par_iter()
        .map(|f| if front[f] { vis_lead[f] } else { vis_trail[f] })
        .collect();
    let contour = contour_line(mesh, contour, &visible);
    let adj = mesh.adjacency();
    let vis = contour
        .par_iter()
        .map(|c| {
            let inc = adj.incident(c.edge as usize);
            let lead = inc
                .iter()
                .any(|&h| front[(h / 3) as usize] && vis_lead[(h / 3) as usize]);
            let trail = inc
                .iter()
                .any(|&h| !front[(h / 3) as usize] && vis_trail[(h / 3) as usize]);
            (lead, trail)
        })
        .collect();
    (contour, vis)
}

/// The ring points `(segment, fraction)` of one contour vertex, trailing (0, 0) to leading (n, 0).
fn ring_points(alpha: &AlphaMode, path: &Path, p: [f64; 3]) -> Vec<(u32, f64)> {
    let n = path.segments();
    match alpha {
        AlphaMode::Coverage(model, q) => {
            let mut out = Vec::with_capacity(n * (q + 2) + 1);
            for j in 0..n {
                out.push((j as u32, 0.0));
                let (p0, p1) = (path.frames[j].point(p), path.frames[j + 1].point(p));
                out.extend(
                    model
                        .knots(j, p0, p1, *q)
                        .into_iter()
                        .map(|u| (j as u32, u)),
                );
            }
            out.push((n as u32, 0.0));
            out
        }
        _ => (0..=n as u32).map(|i| (i, 0.0)).collect(),
    }
}

/// Assemble leading, trailing and joining surfaces (the module docs) with vertex attributes.
#[allow(clippy::too_many_arguments)]
pub(crate) fn assemble(
    mesh: &Mesh,
    path: &Path,
    front: &[bool],
    contour: &[ContourEdge],
    edge_visibility: &[(bool, bool)],
    per_edge: bool,
    alpha: &AlphaMode,
    opts: &VolumeOptions,
) -> Result<MotionVolume> {
    let faces = mesh.faces();
    let verts = mesh.vertices();
    let nv = verts.len();
    let n = path.segments();
    let frames = &path.frames;
    const NONE: u32 = u32::MAX;
    // Ring points per contour vertex.
    let mut ring = vec![NONE; nv];
    let mut ring_vertices = Vec::new();
    for c in contour {
        for i in [c.a, c.b] {
            if ring[i as usize] == NONE {
                ring[i as usize] = ring_vertices.len() as u32;
                ring_vertices.push(i);
            }
        }
    }
    let points: Vec<Vec<(u32, f64)>> = ring_vertices
        .par_iter()
        .map(|&v| ring_points(alpha, path, verts[v as usize]))
        .collect();
    let rings = points.first().map_or(n + 1, |p| p.len());
    let joining = contour.len().saturating_mul(2 * (rings - 1));
    if joining > MAX_ELEMENTS || faces.len() + joining > MAX_ELEMENTS {
        return Err(Error::value(
            "segments",
            format!("{n} segments give too many joining faces"),
        ));
    }
    // Sources: leading, trailing, then ring vertices. Per-face colours give every leading and
    // trailing face its own corners and every joining strip its own vertices.
    let face_colors = matches!(opts.colors, Colors::PerFace(_));
    let strips = per_edge || face_colors;
    let mut lead = vec![NONE; nv];
    let mut trail = vec![NONE; nv];
    if !face_colors {
        for (f, face) in faces.iter().enumerate() {
            let map = if front[f] { &mut lead } else { &mut trail };
            for &i in face {
                map[i as usize] = 0;
            }
        }
    }
    if !strips {
        for &v in &ring_vertices {
            lead[v as usize] = 0;
            trail[v as usize] = 0;
        }
    }
    let mut sources = Vec::new();
    let nr = n as u32;
    let source = |v: u32, (seg, frac): (u32, f64), normal_ring: u32| Source {
        v,
        seg,
        frac,
        normal_ring,
        front: NONE,
        back: NONE,
        towards_front: 1.0,
    };
    let mut out_faces = Vec::with_capacity(faces.len() + joining);
    let mut part = Vec::with_capacity(out_faces.capacity());
    if face_colors {
        for (want, tag, ring) in [(true, LEADING, nr), (false, TRAILING, 0)] {
            for (f, face) in faces.iter().enumerate() {
                if front[f] == want {
                    let base = sources.len() as u32;
                    for &v in face {
                        sources.push(Source {
                            front: f as u32,
                            back: f as u32,
                            ..source(v, (ring, 0.0), ring)
                        });
                    }
                    out_faces.push([base, base + 1, base + 2]);
                    part.push(tag);
                }
            }
        }
    }
    for (v, slot) in lead.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = sources.len() as u32;
            sources.push(source(v as u32, (nr, 0.0), nr));
        }
    }
    for (v, slot) in trail.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = sources.len() as u32;
            sources.push(source(v as u32, (0, 0.0), 0));
        }
    }
    let nearest = |(seg, frac): (u32, f64)| if frac < 0.5 { seg } else { seg + 1 };
    let ring_base = sources.len();
    let ring_count = ring_vertices.len();
    if strips {
        let adj = mesh.adjacency();
        for (k, c) in contour.iter().enumerate() {
            let (vl, vt) = edge_visibility.get(k).copied().unwrap_or((true, true));
            // The strip's front and back faces (a boundary edge has only one).
            let inc = adj.incident(c.edge as usize);
            let pick = |want: bool| {
                inc.iter()
                    .map(|&h| h / 3)
                    .find(|&f| front[f as usize] == want)
            };
            let (ff, fb) = match (pick(true), pick(false)) {
                (Some(x), Some(y)) => (x, y),
                (Some(x), None) | (None, Some(x)) => (x, x),
                (None, None) => (NONE, NONE),
            };
            for r in 0..rings {
                for v in [c.a, c.b] {
                    let pt = points[ring[v as usize] as usize]
                        .get(r)
                        .copied()
                        .unwrap_or((0, 0.0));
                    let normal_ring = match (vl, vt) {
                        (true, false) => nr,
                        (false, true) => 0,
                        _ => nearest(pt),
                    };
                    let towards_front = match (vl, vt) {
                        (true, false) => 1.0,
                        (false, true) => 0.0,
                        _ => ((pt.0 as f64 + pt.1) / n as f64) as f32,
                    };
                    let (front, back) = if face_colors { (ff, fb) } else { (NONE, NONE) };
                    sources.push(Source {
                        front,
                        back,
                        towards_front,
                        ..source(v, pt, normal_ring)
                    });
                }
            }
        }
    } else {
        for r in 1..rings.saturating_sub(1) {
            for (pts, &v) in points.iter().zip(&ring_vertices) {
                sources.push(source(v, pts[r], nearest(pts[r])));
            }
        }
    }
    if sources.len() > MAX_ELEMENTS {
        return Err(Error::value(
            "segments",
            format!("{n} segments give too many vertices"),
        ));
    }
    let id = |k: usize, v: u32, r: usize, which: usize| -> u32 {
        if strips {
            (ring_base + k * 2 * rings + 2 * r + which) as u32
        } else if r == rings - 1 {
            lead[v as usize]
        } else if r == 0 {
            trail[v as usize]
        } else {
            (ring_base + (r - 1) * ring_count + ring[v as usize] as usize) as u32
        }
    };
    if !face_colors {
        for (map, want, tag) in [(&lead, true, LEADING), (&trail, false, TRAILING)] {
            for (f, face) in faces.iter().enumerate() {
                if front[f] == want {
                    out_faces.push([
                        map[face[0] as usize],
                        map[face[1] as usize],
                        map[face[2] as usize],
                    ]);
                    part.push(tag);
                }
            }
        }
    }
    for (k, c) in contour.iter().enumerate() {
        for r in 1..rings {
            let (a0, b0) = (id(k, c.a, r - 1, 0), id(k, c.b, r - 1, 1));
            let (a1, b1) = (id(k, c.a, r, 0), id(k, c.b, r, 1));
            out_faces.push([a0, b0, b1]);
            out_faces.push([a0, b1, a1]);
            part.push(JOINING);
            part.push(JOINING);
        }
    }
    // Attributes.
    let obj_normals = match &opts.normals {
        Some(nr) => nr.clone(),
        None => mesh.vertex_normals(),
    };
    let color = |s: &Source| match &opts.colors {
        Colors::Uniform(c) => *c,
        Colors::PerVertex(c) => c[s.v as usize],
        Colors::PerFace(c) if s.front != NONE => {
            let (f, b, t) = (c[s.front as usize], c[s.back as usize], s.towards_front);
            [0, 1, 2, 3].map(|i| b[i] + (f[i] - b[i]) * t)
        }
        Colors::PerFace(_) => [1.0; 4],
    };
    let place = |s: &Source| {
        let (j, u) = (s.seg as usize, s.frac);
        if u == 0.0 {
            frames[j].point(verts[s.v as usize])
        } else {
            frames[j]
                .interpolate(&frames[j + 1], u)
                .point(verts[s.v as usize])
        }
    };
    let vertices: Vec<[f64; 3]> = sources.par_iter().map(place).collect();
    let filter_alpha = |s: &Source, p: [f64; 3]| match alpha {
        AlphaMode::Rings(r) => r[s.seg as usize],
        AlphaMode::Coverage(model, _) => model.coverage(p),
        AlphaMode::PerVertex(a, w) => (a[s.v as usize] * w[s.seg as usize]).clamp(0.0, 1.0),
    };
    let rgba = sources
        .par_iter()
        .zip(&vertices)
        .map(|(s, p)| {
            let c = color(s);
            [c[0], c[1], c[2], (c[3] as f64 * filter_alpha(s, *p)) as f32]
        })
        .collect();
    let normals = sources
        .par_iter()
        .map(|s| {
            let w = normalize(frames[s.normal_ring as usize].normal(obj_normals[s.v as usize]));
            [w[0] as f32, w[1] as f32, w[2] as f32]
        })
        .collect();
    let ring_alpha = match alpha {
        AlphaMode::Rings(r) => r.clone(),
        _ if ring_vertices.is_empty() => vec![1.0; n + 1],
        _ => (0..=n)
            .map(|i| {
                // Collected first, then summed in order: the same for any thread count.
                let each: Vec<f64> = ring_vertices
                    .par_iter()
                    .map(|&v| {
                        let s = source(v, (i as u32, 0.0), i as u32);
                        filter_alpha(&s, place(&s))
                    })
                    .collect();
                let sum: f64 = each.iter().sum();
                sum / ring_vertices.len() as f64
            })
            .collect(),
    };
    Ok(MotionVolume {
        vertices,
        faces: out_faces,
        rgba,
        normals,
        part,
        ring_alpha,
        contour_edges: contour.len(),
    })
}
