//! Attribute interpolation and shading of one sample.
//!
//! Perspective-correct: the snapped edge functions give screen-space barycentric weights; divided
//! by w at the corners and normalised they become the barycentric coordinates of the surface
//! point in the (original, unclipped) face. Colour, alpha, normals and the homogeneous screen
//! positions used for velocity are interpolated with them.
//!
//! Shading (the definitions the Mitsuba reference reproduces):
//! - `flat`: the interpolated straight colour.
//! - `lambert`: colour * (ambient + sum_l intensity_l * max(0, n . -direction_l)), with `n` the
//!   interpolated, normalised vertex normal, flipped to face the camera on back faces (which only
//!   reach shading when culling is off). Alpha is never shaded.
//!
//! The output colour is premultiplied.
use super::draw::Draw;
use super::interp::Planes;
use super::options::Options;
use super::setup::{Chunk, Tri, FRONT, NO_CLIP};

/// Per-draw data computed once a frame: clip-space positions and previous homogeneous screen
/// positions (for velocity; `clip` is empty without them) and normals (lambert only).
#[derive(Debug, Default)]
pub struct Prepared {
    pub clip: Vec<[f64; 4]>,
    pub prev: Option<Vec<[f64; 3]>>,
    pub normals: Option<Vec<[f32; 3]>>,
}

/// What shading one sample gives.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Shaded {
    /// Premultiplied linear RGBA.
    pub rgba: [f32; 4],
    pub id: i32,
    /// Screen motion since the previous positions, pixels, +x right, +y down.
    pub velocity: [f32; 2],
}

/// Homogeneous pixel position (x w, y w, w) of a clip-space point in an image of `w` x `h`.
#[inline]
pub fn homogeneous_pixel(c: &[f64; 4], w: f64, h: f64) -> [f64; 3] {
    [(c[0] + c[3]) * 0.5 * w, (c[3] - c[1]) * 0.5 * h, c[3]]
}

/// Everything shading needs, shared read-only by the tiles.
pub struct Shader<'a> {
    pub draws: &'a [Draw],
    pub prepared: &'a [Prepared],
    pub chunks: &'a [Chunk],
    pub opts: &'a Options,
    pub width: f64,
    pub height: f64,
}

/// Chunk index and triangle index packed in a triangle reference.
#[inline]
pub fn unpack(r: u32) -> (usize, usize) {
    ((r >> 16) as usize, (r & 0xffff) as usize)
}

impl<'a> Shader<'a> {
    /// What shading the samples of triangle `tri` (reference `r`) needs, gathered once for the
    /// triangle.
    #[inline]
    pub fn prepare(&self, r: u32, tri: &Tri) -> TriShade<'a> {
        let (c, _) = unpack(r);
        let di = tri.draw as usize;
        let d = &self.draws[di];
        let p = &self.prepared[di];
        let v = tri.verts;
        let colors = if d.rgba.len() == 1 {
            None
        } else {
            Some(v.map(|k| d.rgba[k as usize]))
        };
        // a draw's normals are prepared when it is lambert-shaded (its own or the options')
        let normals = p.normals.as_ref().map(|n| v.map(|k| n[k as usize]));
        let mut ts = TriShade {
            constant: None,
            clip: (tri.clip != NO_CLIP).then(|| self.chunks[c].clips[tri.clip as usize]),
            color: d.rgba[0],
            colors,
            normals,
            front: tri.flags & FRONT != 0,
            id: d.object_id,
            verts: v,
            prepared: p,
            opts: self.opts,
            width: self.width,
            height: self.height,
        };
        if ts.colors.is_none() && ts.normals.is_none() && p.prev.is_none() {
            // Nothing varies over the triangle: its one shading, computed as `shade` would.
            ts.constant = Some(ts.shade([0.0; 3]));
        }
        ts
    }
}

/// The shading inputs of one triangle: its corners' colours and normals, its clip table, its
/// draw's id. Per sample only the interpolation remains.
pub struct TriShade<'a> {
    /// The shading of every sample when nothing varies over the triangle (one colour, flat or
    /// without normals, no velocity): `shade` returns it without interpolating.
    constant: Option<Shaded>,
    clip: Option<[[f32; 3]; 3]>,
    /// The draw's colour when it has one for all vertices (`colors` None).
    color: [f32; 4],
    colors: Option<[[f32; 4]; 3]>,
    normals: Option<[[f32; 3]; 3]>,
    front: bool,
    id: i32,
    verts: [u32; 3],
    prepared: &'a Prepared,
    opts: &'a Options,
    width: f64,
    height: f64,
}

impl TriShade<'_> {
    /// Barycentric coordinates in the face of sample (ix, iy), whose interpolation planes are
    /// `planes`.
    #[inline(always)]
    pub fn lambdas(&self, planes: &Planes, ix: i32, iy: i32) -> [f32; 3] {
        let l = planes.lambdas(ix, iy);
        match &self.clip {
            None => [l[0] as f32, l[1] as f32, l[2] as f32],
            Some(b) => {
                let m = |j: usize| {
                    (l[0] * f64::from(b[0][j])
                        + l[1] * f64::from(b[1][j])
                        + l[2] * f64::from(b[2][j])) as f32
                };
                [m(0), m(1), m(2)]
            }
        }
    }

    /// Straight alpha at the sample.
    #[inline]
    pub fn alpha(&self, lam: [f32; 3]) -> f32 {
        match &self.colors {
            None => self.color[3],
            Some(c) => (0..3).map(|k| lam[k] * c[k][3]).sum(),
        }
    }

    /// The shading of sample (ix, iy), whose interpolation planes are `planes` (`shade` of its
    /// `lambdas`, which a constant triangle does not need).
    #[inline(always)]
    pub fn shade_at(&self, planes: &Planes, ix: i32, iy: i32) -> Shaded {
        match self.constant {
            Some(c) => c,
            None => self.shade(self.lambdas(planes, ix, iy)),
        }
    }

    /// The shading of every sample when the triangle's is constant (then its alpha is one
    /// value too).
    #[inline(always)]
    pub fn constant(&self) -> Option<Shaded> {
        self.constant
    }

    /// Shades the sample with barycentric coordinates `lam`.
    #[inline(always)]
    pub fn shade(&self, lam: [f32; 3]) -> Shaded {
        if let Some(c) = self.constant {
            return c;
        }
        let mut c = match &self.colors {
            None => self.color,
            Some(cs) => {
                let mut c = [0.0f32; 4];
                for k in 0..3 {
                    let ck = cs[k];
                    for j in 0..4 {
                        c[j] += lam[k] * ck[j];
                    }
                }
                c
            }
        };
        c[3] = c[3].clamp(0.0, 1.0);
        if let Some(normals) = &self.normals {
            let mut n = [0.0f32; 3];
            for k in 0..3 {
                let nk = normals[k];
                for j in 0..3 {
                    n[j] += lam[k] * nk[j];
                }
            }
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            let s = if len > 0.0 { 1.0 / len } else { 0.0 };
            let s = if self.front { s } else { -s };
            let n = n.map(|x| x * s);
            let mut e = self.opts.ambient;
            for l in &self.opts.lights {
                let cos = -(n[0] * l.direction[0] + n[1] * l.direction[1] + n[2] * l.direction[2]);
                if cos > 0.0 {
                    for j in 0..3 {
                        e[j] += l.intensity[j] * cos;
                    }
                }
            }
            for j in 0..3 {
                c[j] *= e[j];
            }
        }
        let p = self.prepared;
        let v = self.verts;
        let velocity = match &p.prev {
            None => [0.0; 2],
            Some(prev) => {
                let mut cur = [0.0f64; 3];
                let mut old = [0.0f64; 3];
                for k in 0..3 {
                    let h = homogeneous_pixel(&p.clip[v[k] as usize], self.width, self.height);
                    let o = prev[v[k] as usize];
                    let l = f64::from(lam[k]);
                    for j in 0..3 {
                        cur[j] += l * h[j];
                        old[j] += l * o[j];
                    }
                }
                if cur[2] > 0.0 && old[2] > 0.0 {
                    [
                        (cur[0] / cur[2] - old[0] / old[2]) as f32,
                        (cur[1] / cur[2] - old[1] / old[2]) as f32,
                    ]
                } else {
                    [0.0; 2] // the previous position was behind the camera: no defined motion
                }
            }
        };
        let a = c[3];
        Shaded {
            rgba: [c[0] * a, c[1] * a, c[2] * a, a],
            id: self.id,
            velocity,
        }
    }
}
