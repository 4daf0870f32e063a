//! Triangle setup: clip, project, snap to fixed point, cull, orient, bound.
//!
//! Screen coordinates are snapped to 1/256 of a sample (8 sub-pixel bits). Every later coverage
//! decision is exact integer arithmetic on these snapped corners, so the result depends on the
//! vertices alone: a shared edge is drawn exactly once (see `coverage.rs` for the top-left rule).
//!
//! Every vertex is projected and snapped once a frame (`Viewport::project`, a streaming pass);
//! the faces then gather three 8-byte fixed-point positions (prefetched a few faces ahead: a
//! mesh's faces may reach its vertices in any order), the triangles kept after culling and
//! bounds gather the rest of their corners, and only faces that cross the guard band go back to
//! the clip-space positions. A triangle whose box holds at most `TIGHT_MAX` samples gets
//! the box of the samples it covers, or is dropped when it covers none: small triangles then
//! reach fewer tiles, and a box of one sample needs no edge test in the tiles (`ONE_SAMPLE`).
use super::camera::Camera;
use super::clip::{outcode, ClipVertex, ClipVolume, MAX_POLY};
use super::coverage::{Edges, HALF, ONE};
use super::draw::Draw;
use glam::{DMat4, DVec4};

/// The triangle faces the camera (counter-clockwise in OpenGL's y-up window coordinates).
pub const FRONT: u8 = 1;
/// Some fragment may be opaque (alpha >= 1 at some corner).
pub const MAY_OPAQUE: u8 = 2;
/// Some fragment may be transparent (alpha < 1 at some corner).
pub const MAY_TRANSPARENT: u8 = 4;
/// The box is the one sample the triangle covers (set by the small-triangle path).
pub const ONE_SAMPLE: u8 = 8;
/// Unclipped: the corners are the face's vertices `verts`.
pub const NO_CLIP: u32 = u32::MAX;
/// Triangles whose sample box holds at most this many samples get their covered box in setup.
const TIGHT_MAX: i64 = 16;
/// Faces ahead of the current one whose vertices are prefetched.
const PREFETCH: usize = 8;

/// A set-up triangle, oriented so that its fixed-point area is positive (y down).
#[derive(Clone, Copy, Debug)]
pub struct Tri {
    /// Fixed-point sample coordinates of the corners.
    pub x: [i32; 3],
    pub y: [i32; 3],
    /// Unsnapped position minus snapped position, in samples (attributes interpolate from the
    /// exact positions; only coverage uses the snapped ones).
    pub rx: [f32; 3],
    pub ry: [f32; 3],
    /// 1 / w (the inverse view-axis distance) at the corners.
    pub iw: [f32; 3],
    /// Inclusive sample range of the bounding box, clamped to the image (for a small triangle:
    /// the box of the samples it covers).
    pub bbox: [i32; 4],
    /// The face's vertex index of each corner (unclipped), or the face's vertices (clipped).
    pub verts: [u32; 3],
    /// Index of the corners' barycentric coordinates in the chunk's clip table, or NO_CLIP.
    pub clip: u32,
    pub draw: u32,
    pub flags: u8,
}

/// The set-up triangles of a run of faces, in submission order.
#[derive(Default, Debug)]
pub struct Chunk {
    pub tris: Vec<Tri>,
    /// For clipped triangles: the barycentric coordinates of each corner in the face.
    pub clips: Vec<[[f32; 3]; 3]>,
    pub culled: u64,
    pub clipped: u64,
}

/// The internal (supersampled) image the triangles are set up for.
#[derive(Clone, Copy, Debug)]
pub struct Viewport {
    pub ws: u32,
    pub hs: u32,
    pub volume: ClipVolume,
}

impl Viewport {
    pub fn new(ws: u32, hs: u32) -> Self {
        Viewport {
            ws,
            hs,
            volume: ClipVolume::for_size(ws, hs),
        }
    }

    /// Fixed-point position and the residual (exact minus snapped, in samples).
    #[inline]
    fn snap(&self, p: &[f64; 4]) -> Corner {
        let [x, y] = screen(p, self.ws, self.hs);
        let (fx, fy) = ((x * ONE as f64).round(), (y * ONE as f64).round());
        Corner {
            x: fx as i32,
            y: fy as i32,
            rx: (x - fx / ONE as f64) as f32,
            ry: (y - fy / ONE as f64) as f32,
            iw: (1.0 / p[3]) as f32,
        }
    }

    /// A clip-space vertex as the face loop reads it: its fixed-point position, and its
    /// residuals and 1/w. A vertex outside the guard band gets `OUT` for x and its band outcode
    /// for y (its faces are clipped from the clip-space positions).
    #[inline]
    pub fn project(&self, p: &[f64; 4]) -> ([i32; 2], [f32; 3]) {
        let band = outcode(p, self.volume.gx, self.volume.gy);
        if band != 0 {
            return ([OUT, i32::from(band)], [0.0; 3]);
        }
        let c = self.snap(p);
        ([c.x, c.y], [c.rx, c.ry, c.iw])
    }
}

/// A projected corner: fixed-point position, residual, 1/w.
#[derive(Clone, Copy, Debug, Default)]
struct Corner {
    x: i32,
    y: i32,
    rx: f32,
    ry: f32,
    iw: f32,
}

/// The x of a vertex outside the guard band (snapped positions inside it lie within +-2^25).
const OUT: i32 = i32::MIN;

/// A draw's vertices projected once a frame (`Viewport::project`): the fixed-point positions,
/// which every face gathers (8 bytes a vertex), and the residuals and 1/w, which only the
/// triangles that survive culling and bounds gather.
#[derive(Debug, Default)]
pub struct Screen {
    /// Fixed-point (x, y), or (`OUT`, band outcode).
    pub pos: Vec<[i32; 2]>,
    /// Residuals (exact minus snapped, in samples) and 1/w.
    pub attr: Vec<[f32; 3]>,
}

/// Hints the cache to load the elements of `items` that `face`'s vertices index (no effect on
/// any result).
#[inline(always)]
fn prefetch<T>(items: &[T], face: [u32; 3]) {
    #[cfg(target_arch = "x86_64")]
    for i in face {
        if let Some(v) = items.get(i as usize) {
            // SAFETY: a prefetch reads nothing architecturally and cannot fault; the pointer is
            // to a live element anyway.
            unsafe {
                std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(
                    (v as *const T).cast(),
                )
            };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (items, face);
}

#[inline]
fn floor_div(a: i64, b: i64) -> i64 {
    a.div_euclid(b)
}

/// Screen position in samples (x right, y down) of clip-space point `p` on a `ws` x `hs`
/// sample image.
#[inline]
fn screen(p: &[f64; 4], ws: u32, hs: u32) -> [f64; 2] {
    [
        (p[0] / p[3] + 1.0) * 0.5 * f64::from(ws),
        (1.0 - p[1] / p[3]) * 0.5 * f64::from(hs),
    ]
}

/// World points moved, at their clip depth, onto the fixed-point grid the set-up snaps corners
/// to (1/256 of a sample of `camera` at `samples` samples a pixel side): a surface drawn
/// elsewhere (the analytic kernel, which does not snap) then has its edges where this
/// rasterizer puts them. Points behind the camera (w <= 0), beyond 2^15 samples, or when the
/// camera's view-projection has no inverse, are returned as they are.
pub fn on_sample_grid(camera: &Camera, samples: u32, points: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let m = &camera.view_projection();
    let (ws, hs) = (camera.width * samples, camera.height * samples);
    let inv = m.inverse();
    if !inv.is_finite() {
        return points.to_vec();
    }
    let (fw, fh, one) = (f64::from(ws), f64::from(hs), ONE as f64);
    let range = f64::from(1u32 << 15);
    points
        .iter()
        .map(|p| {
            let c = clip_position(m, p);
            let [x, y] = screen(&c, ws, hs);
            if !(c[3] > 0.0 && x.abs() < range && y.abs() < range) {
                return *p;
            }
            let (sx, sy) = ((x * one).round() / one, (y * one).round() / one);
            let (w, z) = (c[3], c[2]);
            let q = inv * DVec4::new((sx / fw * 2.0 - 1.0) * w, (1.0 - sy / fh * 2.0) * w, z, w);
            [q.x / q.w, q.y / q.w, q.z / q.w]
        })
        .collect()
}

/// The clip-space position of world point `p` under the view-projection matrix `m`.
#[inline]
pub fn clip_position(m: &DMat4, p: &[f64; 3]) -> [f64; 4] {
    let c = *m * DVec4::new(p[0], p[1], p[2], 1.0);
    [c.x, c.y, c.z, c.w]
}

/// Sets up faces `faces` (indices into `draw.faces`) of draw `draw_index`, from the projections
/// `screen` of its vertices; faces that cross the guard band are clipped from the clip-space
/// positions under the view-projection matrix `m`.
pub fn setup_chunk(
    draw_index: u32,
    draw: &Draw,
    m: &DMat4,
    screen: &Screen,
    faces: std::ops::Range<usize>,
    vp: &Viewport,
) -> Chunk {
    let mut chunk = Chunk {
        tris: Vec::with_capacity(faces.len()),
        ..Default::default()
    };
    let mut poly = [ClipVertex {
        pos: [0.0; 4],
        bary: [0.0; 3],
    }; MAX_POLY];
    let end = faces.end;
    for fi in faces {
        if fi + PREFETCH < end {
            let ahead = draw.faces[fi + PREFETCH];
            prefetch(&screen.pos, ahead);
            if !draw.cull_back {
                // Without culling most faces are kept and gather the rest of their corners too.
                prefetch(&screen.attr, ahead);
            }
        }
        let face = draw.faces[fi];
        let (amin, amax) = draw.alpha_range(face);
        if amax <= 0.0 {
            continue; // fully transparent everywhere: contributes nothing
        }
        let mut flags = 0u8;
        if amax >= 1.0 {
            flags |= MAY_OPAQUE;
        }
        if amin < 1.0 {
            flags |= MAY_TRANSPARENT;
        }
        let q = face.map(|i| screen.pos[i as usize]);
        if q[0][0] != OUT && q[1][0] != OUT && q[2][0] != OUT {
            // Inside the guard band. A triangle wholly outside the viewport covers no sample
            // centre of the image, which `emit`'s bounds find.
            let attr = || face.map(|i| screen.attr[i as usize]);
            let (x, y) = (q.map(|v| v[0]), q.map(|v| v[1]));
            let kept = Kept {
                face,
                flags,
                bary: None,
            };
            emit(&mut chunk, vp, draw, draw_index, kept, [x, y], attr);
            continue;
        }
        let p = face.map(|i| clip_position(m, &draw.vertices[i as usize]));
        // Trivial reject against the viewport itself (all corners outside one plane).
        if outcode(&p[0], 1.0, 1.0) & outcode(&p[1], 1.0, 1.0) & outcode(&p[2], 1.0, 1.0) != 0 {
            continue;
        }
        let band = q
            .iter()
            .fold(0u8, |b, v| if v[0] == OUT { b | v[1] as u8 } else { b });
        chunk.clipped += 1;
        let n = vp.volume.clip(p, band, &mut poly);
        if n < 3
            || poly[..n]
                .iter()
                .any(|v| !(v.pos[3] > 0.0) || !v.pos.iter().all(|c| c.is_finite()))
        {
            continue;
        }
        for k in 1..n - 1 {
            let idx = [0, k, k + 1];
            let corners = idx.map(|j| vp.snap(&poly[j].pos));
            let bary = idx.map(|j| poly[j].bary.map(|b| b as f32));
            let (x, y) = (corners.map(|k| k.x), corners.map(|k| k.y));
            let attr = || corners.map(|k| [k.rx, k.ry, k.iw]);
            let kept = Kept {
                face,
                flags,
                bary: Some(bary),
            };
            emit(&mut chunk, vp, draw, draw_index, kept, [x, y], attr);
        }
    }
    chunk
}

/// A triangle of a face on its way to `emit`.
#[derive(Clone, Copy)]
struct Kept {
    /// The face's vertices.
    face: [u32; 3],
    /// `MAY_OPAQUE`, `MAY_TRANSPARENT`.
    flags: u8,
    /// For a piece of a clipped face, its corners' barycentric coordinates in the face.
    bary: Option<[[f32; 3]; 3]>,
}

/// Culls, orients and bounds the triangle `kept` of draw `draw_index` with fixed-point corners
/// `[x, y]` (the corners' residuals and 1/w come from `attr`, asked only for a triangle that
/// is kept) and pushes it.
#[inline]
fn emit(
    chunk: &mut Chunk,
    vp: &Viewport,
    draw: &Draw,
    draw_index: u32,
    kept: Kept,
    [mut x, mut y]: [[i32; 3]; 2],
    attr: impl FnOnce() -> [[f32; 3]; 3],
) {
    let Kept {
        face,
        mut flags,
        mut bary,
    } = kept;
    let [a, b, c] = [0, 1, 2].map(|k| (i64::from(x[k]), i64::from(y[k])));
    let area = (b.0 - a.0) * (c.1 - a.1) - (c.0 - a.0) * (b.1 - a.1);
    if area == 0 {
        return;
    }
    // Counter-clockwise in OpenGL's y-up window is a negative area in y-down raster space.
    let front = area < 0;
    if draw.cull_back && !front {
        chunk.culled += 1;
        return;
    }
    let mut verts = face;
    if area < 0 {
        x.swap(1, 2);
        y.swap(1, 2);
        verts.swap(1, 2);
        if let Some(b) = bary.as_mut() {
            // The rows follow the corners; the columns are coordinates in the face's vertices,
            // whose order `verts` just swapped too.
            b.swap(1, 2);
            for row in b.iter_mut() {
                row.swap(1, 2);
            }
        }
    }
    if front {
        flags |= FRONT;
    }
    let xs = x.map(i64::from);
    let ys = y.map(i64::from);
    let lo = |v: [i64; 3]| v[0].min(v[1]).min(v[2]);
    let hi = |v: [i64; 3]| v[0].max(v[1]).max(v[2]);
    // Samples whose centre (i * ONE + HALF) lies inside the bounding box.
    let x0 = (floor_div(lo(xs) - HALF - 1, ONE) + 1).max(0);
    let y0 = (floor_div(lo(ys) - HALF - 1, ONE) + 1).max(0);
    let x1 = floor_div(hi(xs) - HALF, ONE).min(i64::from(vp.ws) - 1);
    let y1 = floor_div(hi(ys) - HALF, ONE).min(i64::from(vp.hs) - 1);
    if x0 > x1 || y0 > y1 {
        return; // covers no sample centre
    }
    let mut bbox = [x0 as i32, y0 as i32, x1 as i32, y1 as i32];
    if (x1 - x0 + 1) * (y1 - y0 + 1) <= TIGHT_MAX {
        match Edges::new(x, y).covered_box(bbox) {
            None => return, // covers no sample
            Some(b) => bbox = b,
        }
        if bbox[0] == bbox[2] && bbox[1] == bbox[3] {
            flags |= ONE_SAMPLE;
        }
    }
    let clip = match bary {
        Some(b) => {
            chunk.clips.push(b);
            (chunk.clips.len() - 1) as u32
        }
        None => NO_CLIP,
    };
    let mut attr = attr();
    if area < 0 {
        attr.swap(1, 2);
    }
    chunk.tris.push(Tri {
        x,
        y,
        rx: attr.map(|k| k[0]),
        ry: attr.map(|k| k[1]),
        iw: attr.map(|k| k[2]),
        bbox,
        verts,
        clip,
        draw: draw_index,
        flags,
    });
}
