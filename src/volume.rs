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
use crate::volume_filter::Filter;
use crate::{Error, Result};

pub const LEADING: u8 = 0;
pub const TRAILING: u8 = 1;
pub const JOINING: u8 = 2;

/// Largest number of segments accepted.
pub const MAX_SEGMENTS: usize = 4096;

/// Per-vertex colours: one straight RGBA for all, or one per mesh vertex.
#[derive(Debug, Clone)]
pub enum Colors {
    Uniform([f32; 4]),
    PerVertex(Vec<[f32; 4]>),
}

/// Options of [`motion_volume`].
#[derive(Debug, Clone)]
pub struct VolumeOptions {
    pub filter: Filter,
    pub colors: Colors,
    /// Per-vertex normals in object space; `None`: area-weighted vertex normals.
    pub normals: Option<Vec<[f64; 3]>>,
    pub camera: Option<[f64; 3]>,
}

impl Default for VolumeOptions {
    fn default() -> Self {
        VolumeOptions {
            filter: Filter::Ramp,
            colors: Colors::Uniform([1.0; 4]),
            normals: None,
            camera: None,
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

/// Where an output vertex comes from: mesh vertex, ring (keyframe) for its position and alpha,
/// keyframe for its normal.
#[derive(Clone, Copy)]
struct Source {
    v: u32,
    ring: u32,
    normal_ring: u32,
}

fn check_options(mesh: &Mesh, opts: &VolumeOptions) -> Result<()> {
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
    let faces = mesh.faces();
    let frames = &path.frames;
    let obj_normals = match &opts.normals {
        Some(nr) => nr.clone(),
        None => mesh.vertex_normals(),
    };
    let color = |v: u32| match &opts.colors {
        Colors::Uniform(c) => *c,
        Colors::PerVertex(c) => c[v as usize],
    };
    let emit = |sources: &[Source],
                alphas: &[f64]|
     -> (Vec<[f64; 3]>, Vec<[f32; 4]>, Vec<[f32; 3]>) {
        let pos = sources
            .par_iter()
            .map(|s| frames[s.ring as usize].point(verts[s.v as usize]))
            .collect();
        let rgba = sources
            .par_iter()
            .map(|s| {
                let c = color(s.v);
                [
                    c[0],
                    c[1],
                    c[2],
                    (c[3] as f64 * alphas[s.ring as usize]) as f32,
                ]
            })
            .collect();
        let nrm = sources
            .par_iter()
            .map(|s| {
                let w = normalize(frames[s.normal_ring as usize].normal(obj_normals[s.v as usize]));
                [w[0] as f32, w[1] as f32, w[2] as f32]
            })
            .collect();
        (pos, rgba, nrm)
    };

    if path.is_static() {
        let sources: Vec<Source> = (0..verts.len() as u32)
            .map(|v| Source {
                v,
                ring: 0,
                normal_ring: 0,
            })
            .collect();
        let alphas = vec![1.0; n + 1];
        let (vertices, rgba, normals) = emit(&sources, &alphas);
        return Ok(MotionVolume {
            vertices,
            faces: faces.to_vec(),
            rgba,
            normals,
            part: vec![LEADING; faces.len()],
            ring_alpha: alphas,
            contour_edges: 0,
        });
    }

    // Motion vector, extent, ring opacities.
    let centroid = {
        let s = verts
            .iter()
            .fold([0.0; 3], |a, v| [a[0] + v[0], a[1] + v[1], a[2] + v[2]]);
        let k = verts.len() as f64;
        [s[0] / k, s[1] / k, s[2] / k]
    };
    let (first, last) = (&frames[0], &frames[n]);
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
    let dir = normalize(total);
    let extent = if dir == [0.0; 3] {
        0.0
    } else {
        // (L_n v) . d = v . (L_n^T d); the translation cancels in max - min.
        let d_obj = last
            .mat3()
            .transpose()
            .mul_vec3(glam::DVec3::from_array(dir))
            .to_array();
        let (lo, hi) = verts
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
    };
    let alphas = opts.filter.ring_alphas(&lengths, extent);

    // Split and contour.
    let front = classify_faces(mesh, m_obj);
    let mut contour = contour_from_sides(mesh, &front);
    let mut edge_visibility: Vec<(bool, bool)> = Vec::new();
    if let Some(eye) = opts.camera {
        let vis_lead = camera_facing(mesh, eye, |p| last.point(p));
        let vis_trail = camera_facing(mesh, eye, |p| first.point(p));
        let visible: Vec<bool> = (0..faces.len())
            .into_par_iter()
            .map(|f| if front[f] { vis_lead[f] } else { vis_trail[f] })
            .collect();
        contour = contour_line(mesh, contour, &visible);
        let adj = mesh.adjacency();
        edge_visibility = contour
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
    }
    let joining = contour.len().checked_mul(2 * n).unwrap_or(usize::MAX);
    if joining > MAX_ELEMENTS || faces.len() + joining > MAX_ELEMENTS {
        return Err(Error::value(
            "segments",
            format!("{n} segments give too many joining faces"),
        ));
    }
    build(
        mesh,
        &front,
        &contour,
        &edge_visibility,
        n,
        opts.camera.is_some(),
        &alphas,
        &emit,
    )
}

#[allow(clippy::too_many_arguments)]
fn build(
    mesh: &Mesh,
    front: &[bool],
    contour: &[ContourEdge],
    edge_visibility: &[(bool, bool)],
    n: usize,
    per_edge: bool,
    alphas: &[f64],
    emit: &(dyn Fn(&[Source], &[f64]) -> (Vec<[f64; 3]>, Vec<[f32; 4]>, Vec<[f32; 3]>) + Sync),
) -> Result<MotionVolume> {
    let faces = mesh.faces();
    let nv = mesh.vertices().len();
    const NONE: u32 = u32::MAX;
    let mut lead = vec![NONE; nv];
    let mut trail = vec![NONE; nv];
    let mut ring = vec![NONE; nv];
    for (f, face) in faces.iter().enumerate() {
        let map = if front[f] { &mut lead } else { &mut trail };
        for &i in face {
            map[i as usize] = 0;
        }
    }
    if !per_edge {
        for c in contour {
            for i in [c.a, c.b] {
                lead[i as usize] = 0;
                trail[i as usize] = 0;
                ring[i as usize] = 0;
            }
        }
    }
    let mut sources = Vec::new();
    let nr = n as u32;
    for (v, slot) in lead.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = sources.len() as u32;
            sources.push(Source {
                v: v as u32,
                ring: nr,
                normal_ring: nr,
            });
        }
    }
    for (v, slot) in trail.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = sources.len() as u32;
            sources.push(Source {
                v: v as u32,
                ring: 0,
                normal_ring: 0,
            });
        }
    }
    let ring_base = sources.len();
    let mut ring_count = 0usize;
    if per_edge {
        for (c, &(vl, vt)) in contour.iter().zip(edge_visibility) {
            for i in 0..=nr {
                let normal_ring = match (vl, vt) {
                    (true, false) => nr,
                    (false, true) => 0,
                    _ => i,
                };
                for v in [c.a, c.b] {
                    sources.push(Source {
                        v,
                        ring: i,
                        normal_ring,
                    });
                }
            }
        }
    } else {
        for slot in ring.iter_mut() {
            if *slot == 0 {
                *slot = ring_count as u32;
                ring_count += 1;
            }
        }
        for i in 1..nr {
            for (v, &slot) in ring.iter().enumerate() {
                if slot != NONE {
                    sources.push(Source {
                        v: v as u32,
                        ring: i,
                        normal_ring: i,
                    });
                }
            }
        }
    }
    if sources.len() > MAX_ELEMENTS {
        return Err(Error::value(
            "segments",
            format!("{n} segments give too many vertices"),
        ));
    }
    let id = |k: usize, v: u32, i: usize, which: usize| -> u32 {
        if per_edge {
            (ring_base + k * 2 * (n + 1) + 2 * i + which) as u32
        } else if i == n {
            lead[v as usize]
        } else if i == 0 {
            trail[v as usize]
        } else {
            (ring_base + (i - 1) * ring_count + ring[v as usize] as usize) as u32
        }
    };
    let mut out_faces = Vec::with_capacity(faces.len() + 2 * n * contour.len());
    let mut part = Vec::with_capacity(out_faces.capacity());
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
    for (k, c) in contour.iter().enumerate() {
        for j in 1..=n {
            let (a0, b0) = (id(k, c.a, j - 1, 0), id(k, c.b, j - 1, 1));
            let (a1, b1) = (id(k, c.a, j, 0), id(k, c.b, j, 1));
            out_faces.push([a0, b0, b1]);
            out_faces.push([a0, b1, a1]);
            part.push(JOINING);
            part.push(JOINING);
        }
    }
    let (vertices, rgba, normals) = emit(&sources, alphas);
    Ok(MotionVolume {
        vertices,
        faces: out_faces,
        rgba,
        normals,
        part,
        ring_alpha: alphas.to_vec(),
        contour_edges: contour.len(),
    })
}
