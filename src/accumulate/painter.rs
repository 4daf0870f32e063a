//! The painter of the time-sampling methods: a fixed set of objects rasterized at any shutter
//! time with the least per-sample work.
//!
//! Objects are grouped by shading mode (groups in the order their first object comes), one
//! rasterizer call per group and the groups composited by depth. Compositing two layers by
//! their nearest depth is exact for opaque surfaces only: when an object is transparent and
//! there are several shading modes, all objects are one group instead (world space, each draw
//! with its own shading), so the rasterizer sorts every transparent surface with the others and
//! the layer is the exact one of the whole scene at that time. A group of one rigid object
//! is drawn in object space: its placement at the time is folded into the view matrix and the
//! lights are turned into object space, so no vertex is touched per sample. Other groups get
//! world vertices (and turned normals) per sample. Placements come from the keyframe engine;
//! the products, determinants and turns follow [`crate::motion`]'s fixed order (numpy's), so a
//! layer equals one drawn from placements computed in numpy, bit for bit.
//!
//! Also here: each object's axis-aligned bounding box, which bounds a rigid object's image
//! at any time (see `frame.rs`).
use std::sync::Arc;

use super::kernels::{composite, Rect};
use crate::error::{Error, Result};
use crate::frame::Frame;
use crate::motion::{
    det3, linear_part, mat4_mul, place, translation_part, transpose_times, turn, Keyframes, Mat3,
    Mat4, IDENTITY4,
};
use crate::raster::{rasterize_over, Blend, Camera, Draw, Light, Options, Shading};
use glam::DMat4;

/// One object of a painter, in object space.
#[derive(Debug, Clone)]
pub struct PaintObject {
    /// Written to the layer's ids where the object is nearest.
    pub id: i32,
    /// Its shading mode.
    pub shading: Shading,
    /// Object-space vertices (V,3), placed by `motion` (world positions when it is None).
    pub vertices: Vec<[f64; 3]>,
    /// Counter-clockwise faces (F,3) over `vertices`; back faces are culled.
    pub faces: Vec<[u32; 3]>,
    /// Straight RGBA, one or one per vertex.
    pub rgba: Vec<[f32; 4]>,
    /// Object-space vertex normals for lambert shading (None: the rasterizer's own).
    pub normals: Option<Vec<[f32; 3]>>,
    /// Rigid keyframes placing the vertices, deforming ones replacing them, or None (still).
    pub motion: Option<Arc<Keyframes>>,
}

impl PaintObject {
    fn deforming(&self) -> bool {
        self.motion.as_ref().is_some_and(|m| m.is_deforming())
    }

    /// The rigid placement at shutter time `t` (the identity for a still or deforming object).
    pub fn placement(&self, t: f64) -> Mat4 {
        self.motion
            .as_ref()
            .map_or(IDENTITY4, |m| m.transform_at(t))
    }

    /// The world vertices at shutter time `t`: `v @ L.T + t` of the placement, the deforming
    /// keyframes' positions, or the vertices themselves.
    pub fn world_vertices(&self, t: f64) -> Vec<[f64; 3]> {
        match &self.motion {
            Some(m) if m.is_deforming() => m.vertices_at(t).expect("deforming keyframes"),
            Some(m) => {
                let p = m.transform_at(t);
                let (l, tr) = (linear_part(&p), translation_part(&p));
                self.vertices.iter().map(|v| place(&l, &tr, v)).collect()
            }
            None => self.vertices.clone(),
        }
    }

    /// The 8 corners of the vertices' axis-aligned box, x slowest and z fastest.
    pub fn box_corners(&self) -> [[f64; 3]; 8] {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for v in &self.vertices {
            for k in 0..3 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
        std::array::from_fn(|i| {
            let pick = |k: usize, bit: usize| if i >> bit & 1 == 0 { lo[k] } else { hi[k] };
            [pick(0, 2), pick(1, 1), pick(2, 0)]
        })
    }
}

trait WithoutVertices {
    /// A copy without its vertices (they are replaced).
    fn clone_without_vertices(&self) -> Draw;
}

impl WithoutVertices for Draw {
    fn clone_without_vertices(&self) -> Draw {
        Draw {
            vertices: Vec::new(),
            faces: self.faces.clone(),
            rgba: self.rgba.clone(),
            normals: self.normals.clone(),
            object_id: self.object_id,
            cull_back: self.cull_back,
            previous: None,
            shading: self.shading,
        }
    }
}

/// The rotation of a placement: its 3x3 part divided by the cube root of its determinant.
fn rotation(m: &Mat4) -> Mat3 {
    let l = linear_part(m);
    let s = det3(&l).cbrt();
    l.map(|row| row.map(|x| x / s))
}

struct Group {
    /// The shading of the rasterizer call (each draw keeps its own, see `Draw::shading`).
    shading: Shading,
    objects: Vec<usize>,
    /// One object drawn in object space.
    object_space: bool,
    /// The group's draws: the same at every sample in object space; in world space the
    /// pattern each sample's draws are made from (new vertices and normals).
    draws: Vec<Draw>,
}

/// Objects drawn at any shutter time (see the module doc).
pub struct Painter {
    objects: Vec<PaintObject>,
    groups: Vec<Group>,
    lights: Vec<([f64; 3], [f64; 3])>,
    ambient: [f32; 3],
}

impl Painter {
    /// A painter of `objects` lit by `lights` (direction the light travels, RGB intensity) and
    /// `ambient`. Errors name the argument (a deforming object's vertex count, lights).
    pub fn new(
        objects: Vec<PaintObject>,
        lights: Vec<([f64; 3], [f64; 3])>,
        ambient: [f64; 3],
    ) -> Result<Self> {
        for (d, k) in &lights {
            Light::new(*d, *k)?;
        }
        if ambient.iter().any(|a| !a.is_finite() || *a < 0.0) {
            return Err(Error::value("ambient", "must be finite and >= 0"));
        }
        let mut groups: Vec<Group> = Vec::new();
        let transparent = objects.iter().any(|o| o.rgba.iter().any(|c| c[3] < 1.0));
        let modes = |s: Shading| objects.iter().any(|o| o.shading == s);
        let one_group = transparent && modes(Shading::Flat) && modes(Shading::Lambert);
        for (i, o) in objects.iter().enumerate() {
            if let Some(crate::motion::Keys::Deforming { count, .. }) =
                o.motion.as_ref().map(|m| m.keys())
            {
                if *count != o.vertices.len() {
                    return Err(Error::shape(
                        "objects",
                        format!(
                            "object {i}: {count} keyframe vertices for {} vertices",
                            o.vertices.len()
                        ),
                    ));
                }
            }
            // one group: lambert for the call, so the lights reach the lambert draws
            let shading = if one_group {
                Shading::Lambert
            } else {
                o.shading
            };
            match groups.iter_mut().find(|g| g.shading == shading) {
                Some(g) => g.objects.push(i),
                None => groups.push(Group {
                    shading,
                    objects: vec![i],
                    object_space: false,
                    draws: Vec::new(),
                }),
            }
        }
        for g in &mut groups {
            g.object_space = g.objects.len() == 1 && !objects[g.objects[0]].deforming();
            g.draws = g
                .objects
                .iter()
                .map(|&i| {
                    let o = &objects[i];
                    Draw {
                        vertices: o.vertices.clone(),
                        faces: o.faces.clone(),
                        rgba: o.rgba.clone(),
                        // a deforming object's normals: the rasterizer's, of its vertices
                        normals: o.normals.clone().filter(|_| !o.deforming()),
                        object_id: o.id,
                        cull_back: true,
                        previous: None,
                        shading: (o.shading != g.shading).then_some(o.shading),
                    }
                })
                .collect();
        }
        Ok(Painter {
            objects,
            groups,
            lights,
            ambient: ambient.map(|a| a as f32),
        })
    }

    /// The objects, in the order given.
    pub fn objects(&self) -> &[PaintObject] {
        &self.objects
    }

    /// The objects at shutter time `t` seen through `view` and `projection` (4x4, row-major)
    /// in a `width` x `height` frame, one sample a pixel (rgba, depth, ids; no velocity).
    pub fn layer(
        &self,
        t: f64,
        view: &Mat4,
        projection: &Mat4,
        width: u32,
        height: u32,
    ) -> Result<Frame> {
        let glam = |m: &Mat4| DMat4::from_cols_array_2d(m).transpose();
        let mut out: Option<Frame> = None;
        for g in &self.groups {
            let mut placed: Vec<Draw> = Vec::new();
            let (vm, lights) = if g.object_space {
                let m = self.objects[g.objects[0]].placement(t);
                let r = rotation(&m);
                let lights: Vec<([f64; 3], [f64; 3])> = self
                    .lights
                    .iter()
                    .map(|(d, k)| (transpose_times(&r, d), *k))
                    .collect();
                (mat4_mul(view, &m), lights)
            } else {
                for (pattern, &i) in g.draws.iter().zip(&g.objects) {
                    let o = &self.objects[i];
                    let mut draw = Draw {
                        vertices: o.world_vertices(t),
                        ..pattern.clone_without_vertices()
                    };
                    if let (Some(n), false) = (&o.normals, o.deforming()) {
                        let r = rotation(&o.placement(t));
                        let turned = n
                            .iter()
                            .map(|v| turn(&r, &v.map(f64::from)).map(|x| x as f32));
                        draw.normals = Some(turned.collect());
                    }
                    placed.push(draw);
                }
                (*view, self.lights.clone())
            };
            let draws = if g.object_space { &g.draws } else { &placed };
            let camera = Camera::from_matrices(glam(&vm), glam(projection), width, height)?;
            let opts = Options {
                samples: 1,
                blend: Blend::Exact,
                shading: g.shading,
                lights: lights
                    .iter()
                    .map(|(d, k)| Light::new(*d, *k))
                    .collect::<Result<_>>()?,
                ambient: self.ambient,
            };
            let (mut layer, _) = rasterize_over(&camera, draws, &opts, None)?;
            if let Some(a) = out {
                let n = layer.depth.len();
                composite(
                    &a.rgba,
                    &a.depth,
                    &a.ids,
                    &mut layer.rgba,
                    &mut layer.depth,
                    &mut layer.ids,
                    Rect::whole(n),
                )?;
            }
            out = Some(layer);
        }
        Ok(out.unwrap_or_else(|| Frame::new(width, height, false)))
    }
}
