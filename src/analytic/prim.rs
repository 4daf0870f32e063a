//! One triangle over one time segment: set-up, bounds and the covered times at a sample.
//!
//! Within a segment every vertex moves linearly in homogeneous pixel space `(x w, y w, w)`:
//! `c(tau) = a + tau d`, `tau` in [0, 1]. For a sample `s = (x, y, 1)` the edge function of the
//! edge from `c_j` to `c_k` is `det[c_j; c_k; s] = s . (c_j x c_k)`, a quadratic in `tau` whose
//! three coefficient vectors are linear in `s`; the orientation `D = det[c_0; c_1; c_2]` is a
//! cubic in `tau` that does not depend on the sample. Counter-clockwise faces (OpenGL's front)
//! have `D < 0` in y-down pixels; with the edge functions negated (`f = -e`), the sample lies
//! inside a front face exactly where `f_0, f_1, f_2 >= 0` and `-D > 0`, and inside a back face
//! where all `f <= 0` and `-D < 0` (homogeneous rasterization: points behind the eye never pass,
//! so no clipping is needed for coverage). The hit point's view depth (its clip `w`) is
//! `-D / (f_0 + f_1 + f_2)`, and `f_i / sum f` are its barycentric coordinates.
//!
//! A triangle whose corners cross the near or far plane during the segment is cut in time per
//! sample: the hit point's `z + w` (near) and `w - z` (far) are `sum f_i g_i / sum f_i` with `g`
//! linear per corner, so two more cubics decide.
//!
//! Without a plane crossing, every corner's image moves on a straight line and the triangle at
//! any instant is the hull of its corners, so the segment's swept image lies in the convex hull
//! of the six end positions: only samples inside it are tested.
use super::hull::convex_hull;
use super::poly::{ceil_i64, cubic_at, floor_i64, quadratic_at, Spans};

/// The prim crosses the near or far plane during its segment (per-sample plane cubics, no hull).
pub const CLIPS: u8 = 1;
/// Every corner is opaque (alpha 1): the prim hides what lies behind it.
pub const OPAQUE: u8 = 2;

type V3 = [f64; 3];

#[inline]
fn cross(p: V3, q: V3) -> V3 {
    [
        p[1] * q[2] - p[2] * q[1],
        p[2] * q[0] - p[0] * q[2],
        p[0] * q[1] - p[1] * q[0],
    ]
}

#[inline]
fn dot(p: V3, q: V3) -> f64 {
    p[0] * q[0] + p[1] * q[1] + p[2] * q[2]
}

#[inline]
fn add(p: V3, q: V3) -> V3 {
    [p[0] + q[0], p[1] + q[1], p[2] + q[2]]
}

#[inline]
fn neg(p: V3) -> V3 {
    [-p[0], -p[1], -p[2]]
}

/// Homogeneous pixel position `(x w, y w, w)` of a clip-space point in an image of `w` x `h`
/// samples (the rasterizer's convention: pixel centres at +0.5, y down).
#[inline]
pub fn homogeneous_pixel(c: &[f64; 4], w: f64, h: f64) -> V3 {
    [(c[0] + c[3]) * 0.5 * w, (c[3] - c[1]) * 0.5 * h, c[3]]
}

/// Up to two spans of local time, single precision (a cubic's sign set on [0, 1]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Facing {
    n: u8,
    s: [[f32; 2]; 2],
}

impl Facing {
    fn from_spans(sp: &Spans) -> Self {
        let mut f = Facing::default();
        for s in sp.as_slice().iter().take(2) {
            f.s[f.n as usize] = [s[0] as f32, s[1] as f32];
            f.n += 1;
        }
        f
    }

    /// The spans in double precision.
    pub fn spans(&self) -> Spans {
        let mut out = Spans::EMPTY;
        for s in &self.s[..self.n as usize] {
            out.push(f64::from(s[0]), f64::from(s[1]));
        }
        out
    }

    /// True when it covers no time.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// True when it is the whole segment.
    pub fn is_full(&self) -> bool {
        self.n == 1 && self.s[0] == [0.0, 1.0]
    }

    /// The span in double precision when there is exactly one (as [`Facing::spans`] has it).
    #[inline]
    pub fn one(&self) -> Option<(f64, f64)> {
        let [a, b] = self.s[0].map(f64::from);
        (self.n == 1 && a < b).then_some((a, b))
    }
}

/// A triangle of one draw over one segment, set up once.
#[derive(Clone, Copy, Debug)]
pub struct Prim {
    /// Index of the draw, of the face in it, and of the segment.
    pub draw: u32,
    pub face: u32,
    pub seg: u32,
    /// `CLIPS`, `OPAQUE`.
    pub flags: u8,
    /// Local times when the face is a front face (`-D > 0`) and, when back faces are drawn,
    /// when it is a back face.
    pub front: Facing,
    pub back: Facing,
    /// Sample bounds `[x0, y0, x1, y1)` of everything the prim can cover.
    pub bbox: [i32; 4],
    /// Convex hull of the six end positions (samples, counter-clockwise in y-down), unless CLIPS.
    pub hull: [[f32; 2]; 6],
    pub nhull: u8,
}

/// Corners of a prim: homogeneous pixel positions at the segment's start (`a`) and their change
/// over it (`d`), and the clip planes' `z + w` and `w - z` at both ends.
#[derive(Clone, Copy, Debug)]
pub struct Corners {
    pub a: [V3; 3],
    pub d: [V3; 3],
    pub near: [[f64; 2]; 3],
    pub far: [[f64; 2]; 3],
}

impl Corners {
    /// From the corners' clip positions at the segment's start and end, for `ws` x `hs` samples.
    pub fn new(c0: [[f64; 4]; 3], c1: [[f64; 4]; 3], ws: f64, hs: f64) -> Self {
        let a = c0.map(|c| homogeneous_pixel(&c, ws, hs));
        let b = c1.map(|c| homogeneous_pixel(&c, ws, hs));
        let d = [0, 1, 2].map(|i| [b[i][0] - a[i][0], b[i][1] - a[i][1], b[i][2] - a[i][2]]);
        let near = [0, 1, 2].map(|i| [c0[i][2] + c0[i][3], c1[i][2] + c1[i][3]]);
        let far = [0, 1, 2].map(|i| [c0[i][3] - c0[i][2], c1[i][3] - c1[i][2]]);
        Corners { a, d, near, far }
    }

    /// The orientation `D(tau) = det[c_0; c_1; c_2]` as cubic coefficients (ascending).
    pub fn orientation(&self) -> [f64; 4] {
        let (a, d) = (self.a, self.d);
        let c0 = dot(a[0], cross(a[1], a[2]));
        let c1 = dot(d[0], cross(a[1], a[2]))
            + dot(a[0], cross(d[1], a[2]))
            + dot(a[0], cross(a[1], d[2]));
        let c2 = dot(a[0], cross(d[1], d[2]))
            + dot(d[0], cross(a[1], d[2]))
            + dot(d[0], cross(d[1], a[2]));
        let c3 = dot(d[0], cross(d[1], d[2]));
        [c0, c1, c2, c3]
    }

    /// True when a corner lies outside the near or far plane at an end of the segment.
    pub fn clips(&self) -> bool {
        self.near
            .iter()
            .chain(&self.far)
            .any(|g| !(g[0] > 0.0 && g[1] > 0.0))
    }
}

/// The sample rows `[y0, y1)` the prim of `corners` can reach, were it set up: the rows of
/// [`setup`]'s bounds (the same arithmetic), or all `hs` rows where it clips or a corner is
/// not finite. A prim [`setup`] drops reaches rows here too.
pub fn rows(corners: &Corners, hs: u32) -> (i32, i32) {
    if corners.clips() {
        return (0, hs as i32);
    }
    let (mut y0, mut y1) = (f64::MAX, f64::MIN);
    for i in 0..3 {
        let (a, d) = (corners.a[i], corners.d[i]);
        let b = add(a, d);
        for y in [a[1] / a[2], b[1] / b[2]] {
            if !y.is_finite() {
                return (0, hs as i32);
            }
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
    }
    let lo = ceil_i64(y0 - 0.5).max(0).min(hs as i64) as i32;
    let hi = floor_i64(y1 - 0.5).saturating_add(1).max(0).min(hs as i64) as i32;
    (lo, hi)
}

/// What [`setup`] finds of a prim: flags, front and back facing, sample bounds, hull and its
/// number of points.
pub type Setup = (u8, Facing, Facing, [i32; 4], [[f32; 2]; 6], u8);

/// Builds the prim of one face over one segment, or None when it can cover nothing: back-facing
/// throughout with culling, degenerate throughout, or outside the image throughout.
pub fn setup(
    corners: &Corners,
    c0: &[[f64; 4]; 3],
    c1: &[[f64; 4]; 3],
    cull_back: bool,
    ws: u32,
    hs: u32,
) -> Option<Setup> {
    // Outside one side of the view volume at both ends (linear motion keeps it there).
    let outside = |f: &dyn Fn(&[f64; 4]) -> bool| c0.iter().chain(c1).all(f);
    if outside(&|c| c[0] > c[3])
        || outside(&|c| c[0] < -c[3])
        || outside(&|c| c[1] > c[3])
        || outside(&|c| c[1] < -c[3])
        || outside(&|c| c[2] < -c[3])
        || outside(&|c| c[2] > c[3])
    {
        return None;
    }
    let dcoef = corners.orientation();
    let front = Spans::signed_cubic(dcoef, -1.0);
    let back = if cull_back {
        Spans::EMPTY
    } else {
        Spans::signed_cubic(dcoef, 1.0)
    };
    if front.is_empty() && back.is_empty() {
        return None;
    }
    let clips = corners.clips();
    let (bbox, hull, nhull) = if clips {
        ([0, 0, ws as i32, hs as i32], [[0.0; 2]; 6], 0)
    } else {
        let mut pts = [[0.0f64; 2]; 6];
        for i in 0..3 {
            let (a, d) = (corners.a[i], corners.d[i]);
            pts[i] = [a[0] / a[2], a[1] / a[2]];
            let b = add(a, d);
            pts[3 + i] = [b[0] / b[2], b[1] / b[2]];
        }
        if pts.iter().flatten().any(|x| !x.is_finite()) {
            return None;
        }
        let (hull, nhull) = convex_hull(&pts);
        let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for p in &pts {
            x0 = x0.min(p[0]);
            y0 = y0.min(p[1]);
            x1 = x1.max(p[0]);
            y1 = y1.max(p[1]);
        }
        // Samples sit at i + 0.5: the first whose centre can be inside, one past the last.
        let lo = |v: f64, n: u32| ceil_i64(v - 0.5).max(0).min(n as i64) as i32;
        let hi = |v: f64, n: u32| floor_i64(v - 0.5).saturating_add(1).max(0).min(n as i64) as i32;
        let bbox = [lo(x0, ws), lo(y0, hs), hi(x1, ws), hi(y1, hs)];
        if bbox[0] >= bbox[2] || bbox[1] >= bbox[3] {
            return None;
        }
        (bbox, hull, nhull)
    };
    let flags = if clips { CLIPS } else { 0 };
    Some((
        flags,
        Facing::from_spans(&front),
        Facing::from_spans(&back),
        bbox,
        hull,
        nhull,
    ))
}

/// A prim's sample-independent coefficients, expanded for the samples of one tile.
#[derive(Clone, Copy, Debug)]
pub struct Edges {
    /// `f_i(tau) = s . (e[i][0] + tau e[i][1] + tau^2 e[i][2])`, the negated edge functions.
    pub e: [[V3; 3]; 3],
    /// The orientation cubic `D` (ascending).
    pub d: [f64; 4],
    /// Per corner: `z + w` and `w - z` at tau = 0 and their change (for CLIPS prims).
    pub near: [[f64; 2]; 3],
    pub far: [[f64; 2]; 3],
}

/// What a simple prim covers at one sample ([`Edges::covered_front`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Cover {
    /// No time.
    Nothing,
    /// One span of local time.
    One(f64, f64),
    /// Several spans (an edge's set had two).
    Many(Spans),
}

/// Per-sample quadratic coefficients `(a, b, c)` of `f_i = a tau^2 + b tau + c`, `i` = 0..2.
pub type SampleEdges = [[f64; 3]; 3];

impl Edges {
    /// Expands the corners' products. The edge opposite corner `i` runs from `j = i + 1` to
    /// `k = i + 2`; a neighbour sharing it runs the other way and gets the exact negation.
    pub fn new(c: &Corners) -> Self {
        let mut e = [[[0.0; 3]; 3]; 3];
        for i in 0..3 {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            let (aj, ak, dj, dk) = (c.a[j], c.a[k], c.d[j], c.d[k]);
            e[i] = [
                neg(cross(aj, ak)),
                neg(add(cross(aj, dk), cross(dj, ak))),
                neg(cross(dj, dk)),
            ];
        }
        let g = |v: [[f64; 2]; 3]| v.map(|p| [p[0], p[1] - p[0]]);
        Edges {
            e,
            d: c.orientation(),
            near: g(c.near),
            far: g(c.far),
        }
    }

    /// The three negated edge functions at sample `(x, y)` (centre coordinates).
    #[inline(always)]
    pub fn at(&self, x: f64, y: f64) -> SampleEdges {
        let ev = |v: V3| v[0] * x + (v[1] * y + v[2]);
        self.e.map(|p| [ev(p[2]), ev(p[1]), ev(p[0])])
    }

    /// The screen gradient of `f_i` at local time `tau` (for the tie rule).
    #[inline]
    fn gradient(&self, i: usize, tau: f64) -> (f64, f64) {
        let p = &self.e[i];
        let g = |k: usize| (p[2][k] * tau + p[1][k]) * tau + p[0][k];
        (g(0), g(1))
    }

    /// The local times when sample `(x, y)` with edge values `q` lies inside the prim as a
    /// front face (`f >= 0`) and as a back face (`f <= 0`), cut by the near and far planes for
    /// CLIPS prims.
    pub fn covered(&self, prim: &Prim, q: &SampleEdges) -> (Spans, Spans) {
        let mut out = Spans::EMPTY;
        let mut out_back = Spans::EMPTY;
        if !prim.front.is_empty() {
            let mut s = if prim.front.is_full() {
                Spans::FULL
            } else {
                prim.front.spans()
            };
            for i in 0..3 {
                let [a, b, c] = q[i];
                let tie = |tau: f64| {
                    let (gx, gy) = self.gradient(i, tau);
                    gx > 0.0 || (gx == 0.0 && gy > 0.0)
                };
                s = s.intersect(&Spans::nonneg_quadratic(a, b, c, tie));
                if s.is_empty() {
                    break;
                }
            }
            if !s.is_empty() && prim.flags & CLIPS != 0 {
                s = s.intersect(&self.planes(q, 1.0));
            }
            out = s;
        }
        if !prim.back.is_empty() {
            let mut s = prim.back.spans();
            for i in 0..3 {
                let [a, b, c] = q[i];
                let tie = |tau: f64| {
                    let (gx, gy) = self.gradient(i, tau);
                    !(gx > 0.0 || (gx == 0.0 && gy > 0.0))
                };
                s = s.intersect(&Spans::nonneg_quadratic(-a, -b, -c, tie));
                if s.is_empty() {
                    break;
                }
            }
            if !s.is_empty() && prim.flags & CLIPS != 0 {
                s = s.intersect(&self.planes(q, -1.0));
            }
            out_back = s;
        }
        (out, out_back)
    }

    /// The one span of local time when the prim is a front face, if it is not clipped and not
    /// drawn from behind: [`Edges::covered_front`] then finds its spans at every sample.
    #[inline]
    pub fn simple(prim: &Prim) -> Option<(f64, f64)> {
        if prim.back.is_empty() && prim.flags & CLIPS == 0 {
            prim.front.one()
        } else {
            None
        }
    }

    /// The front-face case of a simple prim, front-facing during `front`
    /// ([`Edges::simple`]): the same spans as the general [`Edges::covered`], bit for bit,
    /// with no set built while every edge's set is one span.
    #[inline(always)]
    pub fn covered_front(&self, front: (f64, f64), q: &SampleEdges) -> Cover {
        let (mut lo, mut hi) = front;
        for i in 0..3 {
            let [a, b, c] = q[i];
            match Spans::nonneg_quadratic_one(a, b, c, |tau| self.tie(i, tau)) {
                Err((r0, r1)) => return self.covered_front_from(q, i, (lo, hi), (r0, r1)),
                Ok(None) => return Cover::Nothing,
                Ok(Some((l, h))) => {
                    lo = lo.max(l);
                    hi = hi.min(h);
                    if hi <= lo {
                        return Cover::Nothing;
                    }
                }
            }
        }
        Cover::One(lo, hi)
    }

    /// [`Edges::covered_front`] from edge `k`, whose set is `[0, r0]` and `[r1, 1]`, on: the
    /// general form's steps with the edges before `k` already intersected into `[lo, hi]`.
    #[inline(never)]
    fn covered_front_from(
        &self,
        q: &SampleEdges,
        k: usize,
        (lo, hi): (f64, f64),
        (r0, r1): (f64, f64),
    ) -> Cover {
        let mut s = Spans::EMPTY;
        s.push(lo, hi);
        let mut e = Spans::EMPTY;
        e.push(0.0, r0);
        e.push(r1, 1.0);
        s = s.intersect(&e);
        for i in k + 1..3 {
            if s.is_empty() {
                break;
            }
            let [a, b, c] = q[i];
            s = s.intersect(&Spans::nonneg_quadratic(a, b, c, |tau| self.tie(i, tau)));
        }
        if s.is_empty() {
            Cover::Nothing
        } else {
            Cover::Many(s)
        }
    }

    /// The tie rule of front faces for edge `i` at local time `tau` (a sample exactly on the
    /// edge belongs to the side its screen gradient points to).
    #[inline(always)]
    fn tie(&self, i: usize, tau: f64) -> bool {
        let (gx, gy) = self.gradient(i, tau);
        gx > 0.0 || (gx == 0.0 && gy > 0.0)
    }

    /// The parts of the edge functions that depend on the sample row `y` only:
    /// `row[i][k] = e[i][k][1] * y + e[i][k][2]`.
    #[inline]
    pub fn row(&self, y: f64) -> [[f64; 3]; 3] {
        self.e.map(|p| p.map(|v| v[1] * y + v[2]))
    }

    /// [`Edges::at`] from a row's parts: the same values, bit for bit.
    #[inline(always)]
    pub fn at_row(&self, x: f64, row: &[[f64; 3]; 3]) -> SampleEdges {
        let mut q = [[0.0; 3]; 3];
        for i in 0..3 {
            for (k, j) in [(2, 0), (1, 1), (0, 2)] {
                q[i][j] = self.e[i][k][0] * x + row[i][k];
            }
        }
        q
    }

    /// Where the hit point lies between the near and far planes: `sign * sum f_i g_i > 0` for
    /// `g` = `z + w` and `w - z`.
    fn planes(&self, q: &SampleEdges, sign: f64) -> Spans {
        let cubic = |g: &[[f64; 2]; 3]| {
            let mut c = [0.0; 4];
            for i in 0..3 {
                let [a, b, cc] = q[i];
                let [g0, g1] = g[i];
                c[0] += cc * g0;
                c[1] += b * g0 + cc * g1;
                c[2] += a * g0 + b * g1;
                c[3] += a * g1;
            }
            c
        };
        Spans::signed_cubic(cubic(&self.near), sign)
            .intersect(&Spans::signed_cubic(cubic(&self.far), sign))
    }

    /// The view depth (clip w) of the hit point at local time `tau`, or None where the
    /// triangle is edge-on there.
    #[inline]
    pub fn depth(&self, q: &SampleEdges, tau: f64) -> Option<f64> {
        let f = |k: usize| quadratic_at(q[k][0], q[k][1], q[k][2], tau);
        let sum = (f(0) + f(1)) + f(2);
        let w = -cubic_at(self.d, tau) / sum;
        (w > 0.0 && w < f64::INFINITY).then_some(w)
    }

    /// Barycentric coordinates of the hit point at local time `tau`.
    #[inline]
    pub fn barycentric(&self, q: &SampleEdges, tau: f64) -> [f64; 3] {
        let f = q.map(|[a, b, c]| quadratic_at(a, b, c, tau));
        let sum = f[0] + f[1] + f[2];
        if sum == 0.0 {
            return [1.0 / 3.0; 3];
        }
        f.map(|x| x / sum)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small generator of numbers in [0, 1) (no dependency, same sequence everywhere).
    struct Lcg(u64);

    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn the_front_face_path_finds_the_general_spans_bit_for_bit() {
        let mut rng = Lcg(7);
        let (mut many, mut one) = (0, 0);
        for _ in 0..400 {
            // small, fast, turning triangles: edges often change sign twice
            let mut c0 = [[0.0; 4]; 3];
            let mut c1 = [[0.0; 4]; 3];
            for k in 0..3 {
                let w0 = 1.0 + 2.0 * rng.next();
                let w1 = 1.0 + 2.0 * rng.next();
                c0[k] = [rng.next() - 0.5, rng.next() - 0.5, 0.0, w0];
                c1[k] = [rng.next() - 0.5, rng.next() - 0.5, 0.0, w1];
            }
            let corners = Corners::new(c0, c1, 32.0, 32.0);
            // the whole segment, or a part of it as for faces that turn
            let mut front = Spans::EMPTY;
            let (f0, f1) = (rng.next(), rng.next());
            if f0 < 0.3 {
                front.push(0.0, 1.0);
            } else {
                front.push(f0.min(f1) as f32 as f64, f0.max(f1) as f32 as f64);
            }
            let e = Edges::new(&corners);
            let prim = Prim {
                draw: 0,
                face: 0,
                seg: 0,
                flags: 0,
                front: Facing::from_spans(&front),
                back: Facing::default(),
                bbox: [0, 0, 32, 32],
                hull: [[0.0; 2]; 6],
                nhull: 0,
            };
            for y in 0..32 {
                for x in 0..32 {
                    let q = e.at(f64::from(x) + 0.5, f64::from(y) + 0.5);
                    let want = e.covered(&prim, &q).0;
                    let f = Edges::simple(&prim).unwrap();
                    let got = match e.covered_front(f, &q) {
                        Cover::Nothing => Spans::EMPTY,
                        Cover::One(a, b) => {
                            one += 1;
                            let mut s = Spans::EMPTY;
                            s.push(a, b);
                            s
                        }
                        Cover::Many(s) => {
                            many += 1;
                            s
                        }
                    };
                    assert_eq!(got, want, "sample {x},{y}");
                }
            }
        }
        assert!(many > 100 && one > 1000, "{many} {one}");
    }
}
