//! Assembly of motion volumes: the leading, trailing and joining surfaces of a face split and
//! its contour, with placed vertices, colours, normals and filter alphas (see `build.rs`
//! for the construction, `select.rs` for the contour edges swept and `spin.rs` for the spinning
//! case).
use rayon::prelude::*;

use super::coverage::CoverageModel;
use super::refine::{refine, Surface};
use super::sides::{leading_then_trailing, mark_sides};
use super::types::{Colors, MotionVolume, VolumeOptions, JOINING, LEADING, TRAILING};
use crate::contour::ContourEdge;
use crate::error::{Error, Result};
use crate::mesh::{normalize, Mesh, MAX_ELEMENTS};
use crate::motion::{Path, Placer};

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

/// No source, ring point or face.
const NONE: u32 = u32::MAX;

/// A face split swept along a path: what [`assemble`] turns into a volume.
#[derive(Clone, Copy)]
pub(crate) struct Sweep<'a> {
    /// The mesh, in object space.
    pub mesh: &'a Mesh,
    /// Its placements over the shutter.
    pub path: &'a Path,
    /// Per face: leading (placed at close) or trailing (placed at open).
    pub front: &'a [bool],
    /// The contour edges whose joining strips are swept.
    pub contour: &'a [ContourEdge],
    /// Per contour edge, whether its leading and its trailing side face the camera (both, for
    /// an edge past the end).
    pub edge_visibility: &'a [(bool, bool)],
}

/// What the camera sees of a face split: per mesh face, whether it faces the camera at close
/// (`lead`) and at open (`trail`); with `only` ([`VolumeOptions::visible_only`]) the volume
/// keeps only the faces it sees.
#[derive(Clone, Copy)]
pub(crate) struct Seen<'a> {
    pub lead: &'a [bool],
    pub trail: &'a [bool],
    pub only: bool,
}

/// The placements of the mesh's vertices along the path.
struct Places<'a> {
    path: &'a Path,
    verts: &'a [[f64; 3]],
    /// Each keyframe's placer.
    placers: Vec<Placer>,
}

impl<'a> Places<'a> {
    fn new(path: &'a Path, verts: &'a [[f64; 3]]) -> Self {
        let placers = path.frames.iter().map(|f| f.placer()).collect();
        Places {
            path,
            verts,
            placers,
        }
    }

    /// Placement of mesh vertex `v` at `frac` of segment `seg` (a keyframe's own placer at 0).
    fn at(&self, v: u32, (j, u): (u32, f64)) -> [f64; 3] {
        let j = j as usize;
        if u == 0.0 {
            self.placers[j].point(self.verts[v as usize])
        } else {
            self.path.between(j, u).point(self.verts[v as usize])
        }
    }
}

/// The ring points of the contour vertices.
struct Rings {
    /// Per mesh vertex, its index among the contour vertices (`NONE` for the others).
    index: Vec<u32>,
    /// The contour vertices, in the order the contour first reaches them.
    vertices: Vec<u32>,
    /// Each contour vertex's ring points (`ring_points`).
    points: Vec<Vec<(u32, f64)>>,
    /// Ring points per contour vertex.
    count: usize,
    /// The coverage of every ring point, computed once (coverage alphas only): a contour vertex
    /// on two swept edges has its strip vertices at the same points twice, and the rings' mean
    /// alphas read them again.
    coverage: Vec<f64>,
}

impl Rings {
    fn new(sweep: &Sweep, alpha: &AlphaMode, places: &Places) -> Rings {
        let verts = sweep.mesh.vertices();
        let mut index = vec![NONE; verts.len()];
        let mut vertices = Vec::new();
        for c in sweep.contour {
            for i in [c.a, c.b] {
                if index[i as usize] == NONE {
                    index[i as usize] = vertices.len() as u32;
                    vertices.push(i);
                }
            }
        }
        let points: Vec<Vec<(u32, f64)>> = vertices
            .par_iter()
            .map(|&v| ring_points(alpha, sweep.path, verts[v as usize]))
            .collect();
        let count = points
            .first()
            .map_or(sweep.path.segments() + 1, |p| p.len());
        let coverage: Vec<f64> = match alpha {
            AlphaMode::Coverage(model, _) => vertices
                .par_iter()
                .zip(&points)
                .flat_map_iter(|(&v, pts)| {
                    pts.iter().map(move |&pt| model.coverage(places.at(v, pt)))
                })
                .collect(),
            _ => Vec::new(),
        };
        Rings {
            index,
            vertices,
            points,
            count,
            coverage,
        }
    }

    /// Ring point `r` of the `k`-th contour vertex in `coverage` (`NONE` without it).
    fn slot(&self, k: usize, r: usize) -> u32 {
        if self.coverage.is_empty() {
            NONE
        } else {
            (k * self.count + r) as u32
        }
    }
}

/// The source of mesh vertex `v` at ring point `(seg, frac)`, its normal from keyframe
/// `normal_ring`, vertex colours, no ring point.
fn source(v: u32, (seg, frac): (u32, f64), normal_ring: u32) -> Source {
    Source {
        v,
        seg,
        frac,
        normal_ring,
        front: NONE,
        back: NONE,
        towards_front: 1.0,
        ring_point: NONE,
    }
}

/// The keyframe nearest a ring point.
fn nearest((seg, frac): (u32, f64)) -> u32 {
    if frac < 0.5 {
        seg
    } else {
        seg + 1
    }
}

/// The volume's sources and faces as `assemble` builds them.
#[derive(Default)]
struct Parts {
    /// Where each output vertex comes from: leading, trailing, then ring vertices.
    sources: Vec<Source>,
    /// Per mesh vertex, its leading and its trailing source (`NONE` where it has none).
    lead: Vec<u32>,
    trail: Vec<u32>,
    /// The first ring vertex's source.
    ring_base: usize,
    /// Counter-clockwise faces over the sources, and their part (`LEADING`, ...).
    faces: Vec<[u32; 3]>,
    part: Vec<u8>,
}

/// What every step of `assemble` reads.
struct Assembly<'a> {
    sweep: Sweep<'a>,
    alpha: &'a AlphaMode,
    opts: &'a VolumeOptions,
    places: Places<'a>,
    rings: Rings,
    /// Per-face colours: every leading and trailing face has its own corners and every joining
    /// strip its own vertices.
    face_colors: bool,
    /// Every contour edge's strip has its own vertices (per-edge visibility or per-face
    /// colours).
    strips: bool,
}

/// Assemble leading, trailing and joining surfaces (the module docs) with vertex attributes:
/// `sweep` (with `per_edge` each contour edge's strip gets its own vertices, for its own
/// visibility), filter opacities by `alpha`, colours and normals by `opts`, and with `seen`
/// the faces the camera sees.
pub(crate) fn assemble(
    sweep: Sweep,
    per_edge: bool,
    alpha: &AlphaMode,
    opts: &VolumeOptions,
    seen: Option<Seen>,
) -> Result<MotionVolume> {
    let n = sweep.path.segments();
    // 1. The ring points of every contour vertex, and their coverage once.
    let places = Places::new(sweep.path, sweep.mesh.vertices());
    let rings = Rings::new(&sweep, alpha, &places);
    let nfaces = sweep.mesh.faces().len();
    let joining = sweep.contour.len().saturating_mul(2 * (rings.count - 1));
    if joining > MAX_ELEMENTS || nfaces + joining > MAX_ELEMENTS {
        return Err(Error::value(
            "segments",
            format!("{n} segments give too many joining faces"),
        ));
    }
    let face_colors = matches!(opts.colors, Colors::PerFace(_));
    let a = Assembly {
        sweep,
        alpha,
        opts,
        places,
        rings,
        face_colors,
        strips: per_edge || face_colors,
    };
    // 2. Sources: leading, trailing, then ring vertices.
    let mut parts = a.side_sources(joining);
    a.ring_sources(&mut parts.sources);
    if parts.sources.len() > MAX_ELEMENTS {
        return Err(Error::value(
            "segments",
            format!("{n} segments give too many vertices"),
        ));
    }
    // 3. Faces: leading and trailing, then the joining strips.
    a.faces(&mut parts, joining);
    // 4. The faces the camera sees (leading faces facing it at close, trailing ones at open,
    // every joining face); with `Seen::only` only those are kept: the vertices keep their
    // places, and those no face uses skip their coverage alpha (0).
    let front = sweep.front;
    let seen_faces = seen.map(|s| seen_faces(parts.faces.len(), front, s.lead, s.trail));
    let only = seen.is_some_and(|s| s.only);
    let used = seen_faces
        .as_ref()
        .filter(|_| only)
        .map(|seen| keep_seen(seen, &mut parts));
    // The faces whose edges refinement tests: the seen ones (all, without a camera).
    let testable = if only { None } else { seen_faces };
    // 5. Attributes: places, colours, normals and filter alphas.
    let volume = a.attributes(parts, used.as_deref(), testable);
    // 6. The mean filter alpha of every keyframe ring.
    Ok(MotionVolume {
        ring_alpha: a.ring_alpha(),
        ..volume
    })
}

/// Keeps the faces of `parts` that are `seen`; returns per source whether a kept face uses it.
fn keep_seen(seen: &[bool], parts: &mut Parts) -> Vec<bool> {
    let mut k = seen.iter();
    parts.faces.retain(|_| *k.next().unwrap_or(&true));
    let mut k = seen.iter();
    parts.part.retain(|_| *k.next().unwrap_or(&true));
    let mut used = vec![false; parts.sources.len()];
    for f in &parts.faces {
        for &i in f {
            used[i as usize] = true;
        }
    }
    used
}

impl Assembly<'_> {
    /// The leading and trailing sources (per-face colours: with their faces): every mesh vertex
    /// on a leading face at close, on a trailing face at open (the contour vertices too when
    /// they have no strips of their own). Room for `joining` more faces.
    fn side_sources(&self, joining: usize) -> Parts {
        let (faces, front) = (self.sweep.mesh.faces(), self.sweep.front);
        let nv = self.sweep.mesh.vertices().len();
        let rings = &self.rings;
        let mut lead = vec![NONE; nv];
        let mut trail = vec![NONE; nv];
        if !self.face_colors {
            mark_sides(faces, front, &mut lead, &mut trail);
        }
        if !self.strips {
            for &v in &rings.vertices {
                lead[v as usize] = 0;
                trail[v as usize] = 0;
            }
        }
        // At most every mesh vertex twice (or three corners a face), and the strips' vertices.
        let mut sources = Vec::with_capacity(
            if self.face_colors {
                3 * faces.len()
            } else {
                2 * nv
            } + 2 * rings.count * self.sweep.contour.len(),
        );
        let nr = self.sweep.path.segments() as u32;
        let mut out_faces = Vec::with_capacity(faces.len() + joining);
        let mut part = Vec::with_capacity(out_faces.capacity());
        if self.face_colors {
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
        Parts {
            ring_base: sources.len(),
            sources,
            lead,
            trail,
            faces: out_faces,
            part,
        }
    }

    /// The ring vertices' sources: with strips, both ends of every contour edge at every ring
    /// point (normal and per-face colour by the edge's visible sides); without, every contour
    /// vertex at every inner ring point.
    fn ring_sources(&self, sources: &mut Vec<Source>) {
        let rings = &self.rings;
        let (n, nr) = (
            self.sweep.path.segments(),
            self.sweep.path.segments() as u32,
        );
        if !self.strips {
            for r in 1..rings.count.saturating_sub(1) {
                for (k, (pts, &v)) in rings.points.iter().zip(&rings.vertices).enumerate() {
                    sources.push(Source {
                        ring_point: rings.slot(k, r),
                        ..source(v, pts[r], nearest(pts[r]))
                    });
                }
            }
            return;
        }
        let adj = self.sweep.mesh.adjacency();
        let front = self.sweep.front;
        for (k, c) in self.sweep.contour.iter().enumerate() {
            let (vl, vt) = self
                .sweep
                .edge_visibility
                .get(k)
                .copied()
                .unwrap_or((true, true));
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
            for r in 0..rings.count {
                for v in [c.a, c.b] {
                    let pt = rings.points[rings.index[v as usize] as usize]
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
                    let (front, back) = if self.face_colors {
                        (ff, fb)
                    } else {
                        (NONE, NONE)
                    };
                    sources.push(Source {
                        front,
                        back,
                        towards_front,
                        ring_point: rings.slot(rings.index[v as usize] as usize, r),
                        ..source(v, pt, normal_ring)
                    });
                }
            }
        }
    }

    /// The leading and trailing faces over their sources (per-face colours: already made), then
    /// two triangles between consecutive ring points of every contour edge.
    fn faces(&self, parts: &mut Parts, joining: usize) {
        let (faces, front) = (self.sweep.mesh.faces(), self.sweep.front);
        let rings = &self.rings;
        let count = rings.count;
        let ring_count = rings.vertices.len();
        // The source of contour vertex `v` (the `k`-th edge's end `which`) at ring point `r`.
        let id = |k: usize, v: u32, r: usize, which: usize| -> u32 {
            if self.strips {
                (parts.ring_base + k * 2 * count + 2 * r + which) as u32
            } else if r == count - 1 {
                parts.lead[v as usize]
            } else if r == 0 {
                parts.trail[v as usize]
            } else {
                (parts.ring_base + (r - 1) * ring_count + rings.index[v as usize] as usize) as u32
            }
        };
        let mut joined = Vec::with_capacity(joining);
        for (k, c) in self.sweep.contour.iter().enumerate() {
            for r in 1..count {
                let (a0, b0) = (id(k, c.a, r - 1, 0), id(k, c.b, r - 1, 1));
                let (a1, b1) = (id(k, c.a, r, 0), id(k, c.b, r, 1));
                joined.push([a0, b0, b1]);
                joined.push([a0, b1, a1]);
            }
        }
        if !self.face_colors {
            let (sides, leading) = leading_then_trailing(faces, front, &parts.lead, &parts.trail);
            parts.faces = sides;
            parts.faces.reserve(joining);
            parts.part.resize(leading, LEADING);
            parts.part.resize(faces.len(), TRAILING);
        }
        parts.part.resize(parts.faces.len() + joined.len(), JOINING);
        parts.faces.extend(joined);
    }

    /// The filter alpha of source `s` placed at `p`.
    fn filter_alpha(&self, s: &Source, p: [f64; 3]) -> f64 {
        match self.alpha {
            AlphaMode::Rings(r) => r[s.seg as usize],
            AlphaMode::Coverage(_, _) if s.ring_point != NONE => {
                self.rings.coverage[s.ring_point as usize]
            }
            AlphaMode::Coverage(model, _) => model.coverage(p),
            AlphaMode::PerVertex(a, w) => (a[s.v as usize] * w[s.seg as usize]).clamp(0.0, 1.0),
        }
    }

    /// The colour of source `s`.
    fn color(&self, s: &Source) -> [f32; 4] {
        match &self.opts.colors {
            Colors::Uniform(c) => *c,
            Colors::PerVertex(c) => c[s.v as usize],
            Colors::PerFace(c) if s.front != NONE => {
                let (f, b, t) = (c[s.front as usize], c[s.back as usize], s.towards_front);
                [0, 1, 2, 3].map(|i| b[i] + (f[i] - b[i]) * t)
            }
            Colors::PerFace(_) => [1.0; 4],
        }
    }

    /// The volume of `parts`: every source placed, coloured, lit and given its filter alpha
    /// (0 where `used` says no kept face uses it); with coverage alphas the faces are then cut
    /// where they bend (`refine.rs`, testing the edges of the `testable` faces, all when None).
    /// Its ring alphas are left empty.
    fn attributes(
        &self,
        parts: Parts,
        used: Option<&[bool]>,
        testable: Option<Vec<bool>>,
    ) -> MotionVolume {
        let Parts {
            sources,
            faces,
            part,
            ..
        } = parts;
        let obj_normals: &[[f64; 3]] = match &self.opts.normals {
            Some(nr) => nr,
            None => self.sweep.mesh.cached_vertex_normals(),
        };
        let place = |s: &Source| self.places.at(s.v, (s.seg, s.frac));
        let vertices: Vec<[f64; 3]> = sources.par_iter().map(place).collect();
        let placers = &self.places.placers;
        let normals: Vec<[f32; 3]> = sources
            .par_iter()
            .map(|s| {
                let w =
                    normalize(placers[s.normal_ring as usize].normal(obj_normals[s.v as usize]));
                [w[0] as f32, w[1] as f32, w[2] as f32]
            })
            .collect();
        let unused = |i: usize| used.is_some_and(|u| !u[i]);
        let volume = |vertices, faces, part, rgba, normals| MotionVolume {
            vertices,
            faces,
            rgba,
            normals,
            part,
            ring_alpha: Vec::new(),
            contour_edges: self.sweep.contour.len(),
            contour_error: 0.0,
        };
        let AlphaMode::Coverage(model, _) = self.alpha else {
            let rgba = sources
                .par_iter()
                .zip(&vertices)
                .enumerate()
                .map(|(i, (s, p))| {
                    let c = self.color(s);
                    if unused(i) {
                        return [c[0], c[1], c[2], 0.0];
                    }
                    [
                        c[0],
                        c[1],
                        c[2],
                        (c[3] as f64 * self.filter_alpha(s, *p)) as f32,
                    ]
                })
                .collect();
            return volume(vertices, faces, part, rgba, normals);
        };
        // Coverage alphas, then the faces cut where they bend (`refine.rs`).
        let cover = sources
            .par_iter()
            .zip(&vertices)
            .enumerate()
            .map(|(i, (s, p))| {
                if unused(i) {
                    0.0
                } else {
                    self.filter_alpha(s, *p)
                }
            })
            .collect();
        let mut surface = Surface {
            vertices,
            faces,
            part,
            cover,
            colors: sources.par_iter().map(|s| self.color(s)).collect(),
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
        volume(
            surface.vertices,
            surface.faces,
            surface.part,
            rgba,
            surface.normals,
        )
    }

    /// The mean filter alpha of the contour vertices at every keyframe (1 without them).
    fn ring_alpha(&self) -> Vec<f64> {
        let n = self.sweep.path.segments();
        let rings = &self.rings;
        let ring_count = rings.vertices.len();
        match self.alpha {
            AlphaMode::Rings(r) => r.clone(),
            _ if rings.vertices.is_empty() => vec![1.0; n + 1],
            // Ring `i` is ring point `i (q + 2)` of every contour vertex (see `ring_points`).
            AlphaMode::Coverage(_, _) => (0..=n)
                .map(|i| {
                    let r = i * ((rings.count - 1) / n);
                    let sum: f64 = (0..ring_count)
                        .map(|k| rings.coverage[k * rings.count + r])
                        .sum();
                    sum / ring_count as f64
                })
                .collect(),
            _ => (0..=n)
                .map(|i| {
                    // Collected first, then summed in order: the same for any thread count.
                    let each: Vec<f64> = rings
                        .vertices
                        .par_iter()
                        .map(|&v| {
                            let s = source(v, (i as u32, 0.0), i as u32);
                            self.filter_alpha(&s, self.places.at(s.v, (s.seg, s.frac)))
                        })
                        .collect();
                    let sum: f64 = each.iter().sum();
                    sum / ring_count as f64
                })
                .collect(),
        }
    }
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
