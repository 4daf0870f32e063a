//! Shading of a moving triangle at one sample and one instant: the hit point's barycentric
//! coordinates at that instant interpolate colour, alpha and the normal (itself interpolated
//! between the segment's boundaries, so a turning object's lighting turns with it).
//!
//! Definitions are the rasterizer's (`raster/shade.rs`): `flat` is the interpolated straight
//! colour, `lambert` multiplies it by `ambient + sum_l intensity_l * max(0, n . -direction_l)`
//! with `n` normalised and flipped on back faces; alpha is never shaded; the output is
//! premultiplied.
use super::input::{Input, Prepared};
use super::poly::cubic_roots_between;
use super::prim::{homogeneous_pixel, Corners, Edges, Prim, SampleEdges, OPAQUE};
use super::resolve::Layers;
use super::visibility::{Frag, Link, BACK, NONE};
use crate::raster::{Light, Shading};

/// A prim as one tile uses it: its edges and everything shading reads, gathered once.
#[derive(Clone)]
pub struct TilePrim {
    pub edges: Edges,
    /// The prim's draw and face, for velocity.
    pub draw: u32,
    pub face: u32,
    pub flags: u8,
    pub object_id: i32,
    /// Lambert shading (else flat).
    pub lambert: bool,
    /// The segment: shutter time of its start and its length.
    pub t0: f64,
    pub dt: f64,
    /// Straight RGBA of the corners.
    pub colors: [[f32; 4]; 3],
    /// Corner normals at the segment's start and their change over it (lambert).
    pub normals: [[[f32; 3]; 3]; 2],
    /// The draw's colour where it cannot vary ([`Prepared::uniform`]).
    pub uniform: Option<[f32; 4]>,
    /// How much the shading varies across the triangle ([`Quadrature::points`]).
    pub bend: f32,
    /// A light may graze the triangle during its segment (lambert: some corner is lit and some
    /// is not, at some time), so its shading may have a kink ([`Layers::kinks`]).
    pub graze: bool,
}

impl TilePrim {
    /// Gathers what shading `prim` needs.
    pub fn new(input: &Input, prepared: &[Prepared], prim: &Prim, corners: &Corners) -> Self {
        let draw = &input.draws[prim.draw as usize];
        let face = draw.faces[prim.face as usize];
        let d = &prepared[prim.draw as usize];
        let k = prim.seg as usize;
        let colors = face.map(|v| draw.rgba[if draw.rgba.len() == 1 { 0 } else { v as usize }]);
        let mut normals = [[[0.0f32; 3]; 3]; 2];
        if !d.normals.is_empty() {
            for (c, v) in face.iter().enumerate() {
                let (n0, n1) = (
                    d.normals[k * d.nv + *v as usize],
                    d.normals[(k + 1) * d.nv + *v as usize],
                );
                normals[0][c] = n0;
                normals[1][c] = [n1[0] - n0[0], n1[1] - n0[1], n1[2] - n0[2]];
            }
        }
        let (t0, t1) = (input.times[k], input.times[k + 1]);
        let lambert = draw.shading == Shading::Lambert;
        TilePrim {
            edges: Edges::new(corners),
            draw: prim.draw,
            face: prim.face,
            flags: prim.flags,
            object_id: draw.object_id,
            lambert,
            t0,
            dt: t1 - t0,
            colors,
            normals,
            uniform: d.uniform,
            bend: if lambert { spread(&normals) } else { 0.0 },
            graze: lambert && input.shade && grazed(input, &normals),
        }
    }
}

/// The corner terms `n_k(tau) . l` of a light, with `n_k` the corner normal at the segment's
/// start plus `tau` times its change: the term at local time `tau` is `m + tau e`.
#[inline]
fn corner_terms(light: &Light, normals: &[[[f32; 3]; 3]; 2]) -> [(f64, f64); 3] {
    let l = light.direction.map(|x| -f64::from(x));
    let dot =
        |n: [f32; 3]| f64::from(n[0]) * l[0] + f64::from(n[1]) * l[1] + f64::from(n[2]) * l[2];
    [0, 1, 2].map(|k| (dot(normals[0][k]), dot(normals[1][k])))
}

/// Whether the corner terms of the lights that shine take both signs over [`lo`, `hi`] (local
/// time; each term is linear, so its ends tell): only then can a light graze the triangle
/// there (the barycentric weights keep one sign while a sample is inside it).
#[inline]
fn terms_change_sign(terms: &[(f64, f64); 3], lo: f64, hi: f64) -> bool {
    let (mut pos, mut neg) = (false, false);
    for &(m, e) in terms {
        for x in [m + lo * e, m + hi * e] {
            // NaN counts as both
            pos |= !(x <= 0.0);
            neg |= !(x >= 0.0);
        }
    }
    pos && neg
}

/// [`TilePrim::graze`]: some shining light's corner terms change sign over the segment.
fn grazed(input: &Input, normals: &[[[f32; 3]; 3]; 2]) -> bool {
    input.lights.iter().any(|light| {
        light.intensity.iter().any(|x| *x > 0.0)
            && terms_change_sign(&corner_terms(light, normals), 0.0, 1.0)
    })
}

/// The largest distance between two of a triangle's unit corner normals, at the segment's
/// start or end: about the largest angle (radians) between them.
fn spread(normals: &[[[f32; 3]; 3]; 2]) -> f32 {
    let unit = |n: [f32; 3]| {
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        if len > 0.0 {
            n.map(|x| x / len)
        } else {
            n
        }
    };
    let mut most = 0.0f32;
    let (n0, dn) = (normals[0], normals[1]);
    let n1 = [0, 1, 2].map(|c| [0, 1, 2].map(|j| n0[c][j] + dn[c][j]));
    for n in [n0, n1] {
        let u = n.map(unit);
        for (a, b) in [(0, 1), (1, 2), (2, 0)] {
            let d = [0, 1, 2].map(|j| u[a][j] - u[b][j]);
            most = most.max((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt());
        }
    }
    most
}

/// The tile's triangles as seen from one sample.
pub struct SampleShader<'a> {
    pub input: &'a Input<'a>,
    pub prepared: &'a [Prepared<'a>],
    /// The tile's prims, by tile index.
    pub prims: &'a [TilePrim],
    /// The tile's chain links, and per fragment of the sample the link shading reached.
    pub links: &'a [Link],
    pub cursor: Vec<u32>,
    /// Sample centre.
    pub x: f64,
    pub y: f64,
    /// The tile index of the prim shaded last and its edge values at this sample.
    pub last: (u32, SampleEdges),
}

impl SampleShader<'_> {
    #[inline]
    fn prim(&self, p: u32) -> &TilePrim {
        &self.prims[(p & !BACK) as usize]
    }

    /// Starts a sample with `n` fragments.
    pub fn reset(&mut self, n: usize) {
        self.cursor.clear();
        self.cursor.resize(n, NONE);
        self.last.0 = NONE;
    }

    /// Starts loading what shading `frags` reads: the links of their chains and the shading
    /// data of the links' triangles, for fragments whose colour varies (the others are never
    /// shaded). The chains are walked side by side, so the loads of different chains overlap
    /// instead of waiting on each other; the triangles are only prefetched. Nothing is
    /// computed.
    pub fn warm(&mut self, frags: &[Frag]) {
        if !self.input.shade {
            return;
        }
        let walk = &mut self.cursor;
        walk.clear();
        for f in frags {
            let tp = &self.prims[(f.prim & !BACK) as usize];
            if tp.uniform.is_none() {
                prefetch(tp);
                if f.n > 1 {
                    walk.push(f.chain);
                }
            }
        }
        while !walk.is_empty() {
            let mut kept = 0;
            for k in 0..walk.len() {
                let l = &self.links[walk[k] as usize];
                if l.next != NONE {
                    prefetch(&self.prims[self.links[l.next as usize].prim as usize]);
                    walk[kept] = l.next;
                    kept += 1;
                }
            }
            walk.truncate(kept);
        }
    }

    /// The triangle of `f`'s chain covering the sample at time `t` (with `f`'s `BACK` flag).
    pub fn prim_at(&self, f: &Frag, t: f64) -> u32 {
        let mut c = f.chain;
        loop {
            let next = self.links[c as usize].next;
            if next == NONE || f64::from(self.links[next as usize].t0) > t {
                return self.links[c as usize].prim | (f.prim & BACK);
            }
            c = next;
        }
    }

    /// Barycentric coordinates of the surface point at this sample at time `t`, and the
    /// local time.
    #[inline]
    fn barycentric(&self, tp: &TilePrim, t: f64) -> ([f64; 3], f64) {
        let q = tp.edges.at(self.x, self.y);
        barycentric_at(tp, &q, t)
    }

    /// Object id of the prim's draw.
    pub fn object_id(&self, p: u32) -> i32 {
        self.prim(p).object_id
    }

    /// Screen motion over the shutter (pixels, +x right, +y down) of the surface point seen at
    /// this sample at time `t`: the same barycentric point at the first and last boundary.
    pub fn velocity(&self, p: u32, t: f64) -> [f32; 2] {
        let tp = self.prim(p);
        let (lam, _) = self.barycentric(tp, t);
        let d = &self.prepared[tp.draw as usize];
        let face = self.input.draws[tp.draw as usize].faces[tp.face as usize];
        let s = f64::from(self.input.samples);
        let (ws, hs) = (
            f64::from(self.input.width) * s,
            f64::from(self.input.height) * s,
        );
        let at = |k: usize| {
            let mut h = [0.0f64; 3];
            for c in 0..3 {
                let hp = homogeneous_pixel(&d.clip_at(k, face[c] as usize), ws, hs);
                for j in 0..3 {
                    h[j] += lam[c] * hp[j];
                }
            }
            h
        };
        let (h0, h1) = (at(0), at(self.input.times.len() - 1));
        if h0[2] > 0.0 && h1[2] > 0.0 {
            [
                ((h1[0] / h1[2] - h0[0] / h0[2]) / s) as f32,
                ((h1[1] / h1[2] - h0[1] / h0[2]) / s) as f32,
            ]
        } else {
            [0.0; 2]
        }
    }
}

/// Asks the CPU to bring `tp`'s edges and shading data into cache (a hint, no effect on
/// results).
#[inline(always)]
fn prefetch(tp: &TilePrim) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let base = (tp as *const TilePrim).cast::<i8>();
        let mut k = 0;
        while k < std::mem::size_of::<TilePrim>() {
            // SAFETY: a prefetch never faults; the address is inside `tp`.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(base.wrapping_add(k)) };
            k += 64;
        }
    }
}

/// Barycentric coordinates of the surface point with edge values `q` at time `t`, and the
/// local time.
#[inline]
fn barycentric_at(tp: &TilePrim, q: &SampleEdges, t: f64) -> ([f64; 3], f64) {
    // dividing by 1 (one segment over the whole shutter) changes nothing: skip it
    let d = t - tp.t0;
    let tau = if tp.dt == 1.0 { d } else { d / tp.dt }.clamp(0.0, 1.0);
    (tp.edges.barycentric(q, tau), tau)
}

impl Layers for SampleShader<'_> {
    #[inline]
    fn opaque(&self, f: &Frag) -> bool {
        self.prim(f.prim).flags & OPAQUE != 0
    }

    #[inline]
    fn uniform(&self, f: &Frag) -> Option<[f32; 4]> {
        // a chain's triangles are all of one draw
        self.prim(f.prim).uniform
    }

    #[inline]
    fn cuts(&mut self, i: usize, f: &Frag, a: f64, b: f64, out: &mut Vec<f64>) {
        let mut c = if self.cursor[i] == NONE {
            f.chain
        } else {
            self.cursor[i]
        };
        loop {
            let next = self.links[c as usize].next;
            if next == NONE {
                return;
            }
            let t = f64::from(self.links[next as usize].t0);
            if t >= b {
                return;
            }
            if t > a {
                out.push(t);
            }
            c = next;
        }
    }

    #[inline]
    fn triangle(&mut self, i: usize, f: &Frag, t: f64) -> (u32, f64) {
        let mut c = if self.cursor[i] == NONE {
            f.chain
        } else {
            self.cursor[i]
        };
        loop {
            let next = self.links[c as usize].next;
            if next == NONE {
                self.cursor[i] = c;
                return (self.links[c as usize].prim | (f.prim & BACK), f64::INFINITY);
            }
            let end = f64::from(self.links[next as usize].t0);
            if end > t {
                self.cursor[i] = c;
                return (self.links[c as usize].prim | (f.prim & BACK), end);
            }
            c = next;
        }
    }

    fn kinks(&mut self, p: u32, a: f64, b: f64, out: &mut Vec<f64>) {
        let tp = &self.prims[(p & !BACK) as usize];
        if !tp.graze {
            return;
        }
        // local times of the piece within the prim's segment
        let (lo, hi) = (
            ((a - tp.t0) / tp.dt).clamp(0.0, 1.0),
            ((b - tp.t0) / tp.dt).clamp(0.0, 1.0),
        );
        if !(hi > lo) {
            return;
        }
        for light in self.input.lights {
            if light.intensity.iter().all(|x| *x <= 0.0) {
                continue;
            }
            // n(tau) . l with n = sum_k f_k(tau) (n0_k + tau dn_k) (the barycentric weights
            // before their positive normalisation): a cubic in the local time, which can only
            // change sign where the corner terms do
            let terms = corner_terms(light, &tp.normals);
            if !terms_change_sign(&terms, lo, hi) {
                continue;
            }
            if self.last.0 != p & !BACK {
                self.last = (p & !BACK, tp.edges.at(self.x, self.y));
            }
            let q = self.last.1;
            let mut c = [0.0f64; 4];
            for k in 0..3 {
                let [qa, qb, qc] = q[k];
                let (m, e) = terms[k];
                c[0] += qc * m;
                c[1] += qb * m + qc * e;
                c[2] += qa * m + qb * e;
                c[3] += qa * e;
            }
            let (r, n) = cubic_roots_between(c, lo, hi);
            for &tau in &r[..n] {
                let t = tp.t0 + tau * tp.dt;
                if t > a && t < b {
                    out.push(t);
                }
            }
        }
    }

    #[inline]
    fn bend(&self, p: u32) -> f32 {
        self.prim(p).bend
    }

    #[inline(always)]
    fn shade(&mut self, p: u32, t: f64) -> [f32; 4] {
        let input = self.input;
        if !input.shade {
            return [1.0; 4];
        }
        let prims = self.prims;
        let tp = &prims[(p & !BACK) as usize];
        // the prim's edge values at this sample, kept while calls stay on one prim
        if self.last.0 != p & !BACK {
            self.last = (p & !BACK, tp.edges.at(self.x, self.y));
        }
        let (lam, tau) = barycentric_at(tp, &self.last.1, t);
        let mut c = [0.0f32; 4];
        for k in 0..3 {
            for j in 0..4 {
                c[j] += lam[k] as f32 * tp.colors[k][j];
            }
        }
        c[3] = c[3].clamp(0.0, 1.0);
        if tp.lambert {
            let mut n = [0.0f32; 3];
            for (k, l) in lam.iter().enumerate() {
                let (n0, dn) = (tp.normals[0][k], tp.normals[1][k]);
                for j in 0..3 {
                    n[j] += *l as f32 * (n0[j] + tau as f32 * dn[j]);
                }
            }
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            let s = if len > 0.0 { 1.0 / len } else { 0.0 };
            let s = if p & BACK != 0 { -s } else { s };
            let n = n.map(|x| x * s);
            let mut l = input.ambient;
            for light in input.lights {
                let cos = -(n[0] * light.direction[0]
                    + n[1] * light.direction[1]
                    + n[2] * light.direction[2]);
                if cos > 0.0 {
                    for j in 0..3 {
                        l[j] += light.intensity[j] * cos;
                    }
                }
            }
            for j in 0..3 {
                c[j] *= l[j];
            }
        }
        let a = c[3];
        [c[0] * a, c[1] * a, c[2] * a, a]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_is_the_largest_chord_between_unit_corner_normals() {
        // equal normals (of any length) do not bend; a right angle is a chord of sqrt(2)
        let flat = [[[0.0, 0.0, 2.0]; 3], [[0.0; 3]; 3]];
        assert_eq!(spread(&flat), 0.0);
        let bent = [
            [[0.0, 0.0, 1.0], [0.0, 0.0, 3.0], [0.0, 1.0, 0.0]],
            [[0.0; 3]; 3],
        ];
        assert!((spread(&bent) - 2f32.sqrt()).abs() < 1e-6);
        // a segment that bends its corners apart counts at its end
        let mut turning = flat;
        turning[1][2] = [0.0, 1.0, -2.0];
        assert!((spread(&turning) - 2f32.sqrt()).abs() < 1e-6);
    }
}
