//! Assembly of motion volumes: the leading, trailing and joining surfaces of a face split and
//! its contour, with placed vertices, colours, normals and filter alphas (see `build.rs`
//! for the construction and `spin.rs` for the spinning case).
use rayon::prelude::*;

use super::coverage::CoverageModel;
use super::refine::{refine, Surface};
use super::sides::{leading_then_trailing, mark_sides};
use super::types::{Colors, MotionVolume, VolumeOptions, JOINING, LEADING, TRAILING};
use crate::contour::{contour_line, ContourEdge};
use crate::error::{Error, Result};
use crate::mesh::{normalize, Mesh, MAX_ELEMENTS};
use crate::motion::Path;

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
    /// A ring point's index among all contour vertices' ring points (its coverage is computed
    /// once, see `assemble`), or `u32::MAX`.
    ring_point: u32,
}

/// How the vertices of a volume get their filter opacity.
pub(crate) enum AlphaMode {
    /// One opacity per keyframe ring (the paper's ramp); no extra cuts in the joining strips.
    Rings(Vec<f64>),
    /// The coverage model; every joining segment is cut at `q + 1` per-vertex times.
    Coverage(Box<CoverageModel>, usize),
    /// One opacity per mesh vertex times a weight per keyframe ring (see `spin.rs`).
    PerVertex(Vec<f64>, Vec<f64>),
}

/// The `contour` edges of a face split (from `front`); with the camera sides of the faces
/// (facing the camera at close, at open), the contour line and, per edge, whether its leading
/// (front faces at close) and trailing (back faces at open) sides face the camera.
///
/// With `strips` (the path and the eye, for a path that turns) an edge is also kept when a
/// triangle of its joining strip between two keyframes faces the eye: a turning object shows
/// strips of edges whose faces face away both at close (leading side) and at open (trailing
/// side), and dropping them emptied the frame of a box that turned 1.4 rad while moving 2 units
/// (the section 3.2 contour line assumes a translation).
pub(crate) fn select_contour(
    mesh: &Mesh,
    contour: Vec<ContourEdge>,
    front: &[bool],
    sides: Option<&(Vec<bool>, Vec<bool>)>,
    strips: Option<(&Path, [f64; 3])>,
) -> (Vec<ContourEdge>, Vec<(bool, bool)>) {
    let Some((vis_lead, vis_trail)) = sides else {
        return (contour, Vec::new());
    };
    let visible: Vec<bool> = (0..front.len())
        .into_par_iter()
        .map(|f| if front[f] { vis_lead[f] } else { vis_trail[f] })
        .collect();
    let contour = match strips {
        None => contour_line(mesh, contour, &visible),
        Some((path, eye)) => {
            let adj = mesh.adjacency();
            let verts = mesh.vertices();
            contour
                .into_par_iter()
                .filter(|c| {
                    adj.incident(c.edge as usize)
                        .iter()
                        .any(|&h| visible[(h / 3) as usize])
                        || strip_faces(path, verts[c.a as usize], verts[c.b as usize], eye)
                })
                .collect()
        }
    };
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

/// Whether a triangle of the joining strip of the edge `(a, b)` (object space) between two
/// keyframes of `path` faces `eye`, as `assemble` emits them: `a0 b0 b1` and `a0 b1 a1`,
/// counter-clockwise.
fn strip_faces(path: &Path, a: [f64; 3], b: [f64; 3], eye: [f64; 3]) -> bool {
    let sub = |p: [f64; 3], q: [f64; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
    let cross = |u: [f64; 3], v: [f64; 3]| {
        [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ]
    };
    let facing = |p: [f64; 3], q: [f64; 3], r: [f64; 3]| {
        crate::mesh::dot(cross(sub(q, p), sub(r, p)), sub(eye, p)) > 0.0
    };
    path.frames.windows(2).any(|w| {
        let (a0, b0) = (w[0].point(a), w[0].point(b));
        let (a1, b1) = (w[1].point(a), w[1].point(b));
        facing(a0, b0, b1) || facing(a0, b1, a1)
    })
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
    facing: Option<(&[bool], &[bool])>,
    visible_only: bool,
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
    // Placement of mesh vertex `v` at `frac` of segment `seg` (a keyframe's own placer at 0).
    let placers: Vec<_> = frames.iter().map(|f| f.placer()).collect();
    let place_at = |v: u32, (j, u): (u32, f64)| {
        let j = j as usize;
        if u == 0.0 {
            placers[j].point(verts[v as usize])
        } else {
            path.between(j, u).point(verts[v as usize])
        }
    };
    // The coverage of every ring point, once: a contour vertex on two swept edges has its
    // strip vertices at the same points twice, and the rings' mean alphas read them again.
    let ring_coverage: Vec<f64> = match alpha {
        AlphaMode::Coverage(model, _) => ring_vertices
            .par_iter()
            .zip(&points)
            .flat_map_iter(|(&v, pts)| pts.iter().map(move |&pt| model.coverage(place_at(v, pt))))
            .collect(),
        _ => Vec::new(),
    };
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
        mark_sides(faces, front, &mut lead, &mut trail);
    }
    if !strips {
        for &v in &ring_vertices {
            lead[v as usize] = 0;
            trail[v as usize] = 0;
        }
    }
    // At most every mesh vertex twice (or three corners a face), and the strips' vertices.
    let mut sources = Vec::with_capacity(
        if face_colors { 3 * faces.len() } else { 2 * nv } + 2 * rings * contour.len(),
    );
    let nr = n as u32;
    let source = |v: u32, (seg, frac): (u32, f64), normal_ring: u32| Source {
        v,
        seg,
        frac,
        normal_ring,
        front: NONE,
        back: NONE,
        towards_front: 1.0,
        ring_point: NONE,
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
    // Ring point `r` of the `k`-th contour vertex in `ring_coverage` (none without it).
    let slot = |k: usize, r: usize| {
        if ring_coverage.is_empty() {
            NONE
        } else {
            (k * rings + r) as u32
        }
    };
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
                        ring_point: slot(ring[v as usize] as usize, r),
                        ..source(v, pt, normal_ring)
                    });
                }
            }
        }
    } else {
        for r in 1..rings.saturating_sub(1) {
            for (k, (pts, &v)) in points.iter().zip(&ring_vertices).enumerate() {
                sources.push(Source {
                    ring_point: slot(k, r),
                    ..source(v, pts[r], nearest(pts[r]))
                });
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
        let (sides, leading) = leading_then_trailing(faces, front, &lead, &trail);
        out_faces = sides;
        out_faces.reserve(joining);
        part.resize(leading, LEADING);
        part.resize(faces.len(), TRAILING);
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
    // The faces the camera sees (leading faces facing it at close, trailing ones at open, every
    // joining face); with `VolumeOptions::visible_only` only those are kept: the vertices keep
    // their places, and those no face uses skip their coverage alpha (0).
    let seen = facing.map(|(lead, trail)| seen_faces(out_faces.len(), front, lead, trail));
    let used = seen.as_ref().filter(|_| visible_only).map(|seen| {
        let mut k = seen.iter();
        out_faces.retain(|_| *k.next().unwrap_or(&true));
        let mut k = seen.iter();
        part.retain(|_| *k.next().unwrap_or(&true));
        let mut used = vec![false; sources.len()];
        for f in &out_faces {
            for &i in f {
                used[i as usize] = true;
            }
        }
        used
    });
    // The faces whose edges refinement tests: the seen ones (all, without a camera).
    let testable = if visible_only { None } else { seen };
    // Attributes.
    let obj_normals: &[[f64; 3]] = match &opts.normals {
        Some(nr) => nr,
        None => mesh.cached_vertex_normals(),
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
    let place = |s: &Source| place_at(s.v, (s.seg, s.frac));
    let vertices: Vec<[f64; 3]> = sources.par_iter().map(place).collect();
    let filter_alpha = |s: &Source, p: [f64; 3]| match alpha {
        AlphaMode::Rings(r) => r[s.seg as usize],
        AlphaMode::Coverage(_, _) if s.ring_point != NONE => ring_coverage[s.ring_point as usize],
        AlphaMode::Coverage(model, _) => model.coverage(p),
        AlphaMode::PerVertex(a, w) => (a[s.v as usize] * w[s.seg as usize]).clamp(0.0, 1.0),
    };
    let normals: Vec<[f32; 3]> = sources
        .par_iter()
        .map(|s| {
            let w = normalize(placers[s.normal_ring as usize].normal(obj_normals[s.v as usize]));
            [w[0] as f32, w[1] as f32, w[2] as f32]
        })
        .collect();
    let (vertices, out_faces, part, rgba, normals) = match alpha {
        AlphaMode::Coverage(model, _) => {
            // Coverage alphas, then the faces cut where they bend (`refine.rs`).
            let cover = sources
                .par_iter()
                .zip(&vertices)
                .enumerate()
                .map(|(i, (s, p))| {
                    if used.as_ref().is_some_and(|u| !u[i]) {
                        0.0
                    } else {
                        filter_alpha(s, *p)
                    }
                })
                .collect();
            let mut surface = Surface {
                vertices,
                faces: out_faces,
                part,
                cover,
                colors: sources.par_iter().map(color).collect(),
                normals,
                testable: testable.unwrap_or_default(),
            };
            refine(model, &mut surface);
            let rgba = surface
                .colors
                .par_iter()
                .zip(&surface.cover)
                .map(|(c, a)| [c[0], c[1], c[2], (c[3] as f64 * a) as f32])
                .collect();
            (
                surface.vertices,
                surface.faces,
                surface.part,
                rgba,
                surface.normals,
            )
        }
        _ => {
            let rgba = sources
                .par_iter()
                .zip(&vertices)
                .enumerate()
                .map(|(i, (s, p))| {
                    let c = color(s);
                    if used.as_ref().is_some_and(|u| !u[i]) {
                        return [c[0], c[1], c[2], 0.0];
                    }
                    [c[0], c[1], c[2], (c[3] as f64 * filter_alpha(s, *p)) as f32]
                })
                .collect();
            (vertices, out_faces, part, rgba, normals)
        }
    };
    let ring_alpha = match alpha {
        AlphaMode::Rings(r) => r.clone(),
        _ if ring_vertices.is_empty() => vec![1.0; n + 1],
        // Ring `i` is ring point `i (q + 2)` of every contour vertex (see `ring_points`).
        AlphaMode::Coverage(_, _) => (0..=n)
            .map(|i| {
                let r = i * ((rings - 1) / n);
                let sum: f64 = (0..ring_count).map(|k| ring_coverage[k * rings + r]).sum();
                sum / ring_count as f64
            })
            .collect(),
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
        contour_error: 0.0,
    })
}

/// Per face of the `count` a volume has, whether the camera sees it: the leading faces facing it
/// at close (`lead`), the trailing faces facing it at open (`trail`) and every joining face.
/// `assemble` emits the leading faces first, then the trailing ones, each in mesh-face order,
/// then the joining strips.
fn seen_faces(count: usize, front: &[bool], lead: &[bool], trail: &[bool]) -> Vec<bool> {
    let seen = front
        .iter()
        .zip(lead)
        .filter(|(f, _)| **f)
        .map(|(_, v)| *v)
        .chain(
            front
                .iter()
                .zip(trail)
                .filter(|(f, _)| !**f)
                .map(|(_, v)| *v),
        );
    debug_assert!(count >= front.len());
    seen.chain(std::iter::repeat(true)).take(count).collect()
}
