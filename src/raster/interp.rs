//! Interpolation planes of a set-up triangle.
//!
//! Coverage is decided on the snapped fixed-point corners (`tile.rs`), but attributes and depth
//! are interpolated from the exact (unsnapped) screen positions, as OpenGL implementations do:
//! snapping moves a corner by up to 1/512 sample, which on a grazing surface would change the
//! depth by far more than the 1e-4 relative accuracy we hold.
//!
//! Screen-space barycentric weights b_k are affine in the sample position; 1/w is affine too
//! (sum of b_k / w_k), and the perspective-correct barycentric coordinates of the surface point
//! are (b_k / w_k) / (1/w).
use super::coverage::ONE;
use super::setup::Tri;

/// Affine planes of the three screen-space weights, relative to corner 0, plus 1/w.
#[derive(Clone, Copy, Debug)]
pub struct Planes {
    ox: f64,
    oy: f64,
    /// b_k(p) = gx[k] * (px - ox) + gy[k] * (py - oy) + g0[k]
    gx: [f64; 3],
    gy: [f64; 3],
    g0: [f64; 3],
    iw: [f64; 3],
    /// 1/w(p) = wx * (px - ox) + wy * (py - oy) + w0
    wx: f64,
    wy: f64,
    w0: f64,
}

impl Planes {
    #[inline]
    pub fn new(t: &Tri) -> Self {
        let one = ONE as f64;
        let exact = |k: usize| {
            (
                f64::from(t.x[k]) / one + f64::from(t.rx[k]),
                f64::from(t.y[k]) / one + f64::from(t.ry[k]),
            )
        };
        let snapped = |k: usize| (f64::from(t.x[k]) / one, f64::from(t.y[k]) / one);
        let area = |p: [(f64, f64); 3]| {
            (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (p[1].1 - p[0].1)
        };
        let mut p = [exact(0), exact(1), exact(2)];
        let mut a = area(p);
        // The triangle is oriented with a positive snapped area; a sliver whose exact area has
        // the other sign (or none) interpolates on its snapped corners instead.
        if !(a > 0.0) {
            p = [snapped(0), snapped(1), snapped(2)];
            a = area(p);
        }
        let (ox, oy) = p[0];
        let inv = 1.0 / a;
        let mut pl = Planes {
            ox,
            oy,
            gx: [0.0; 3],
            gy: [0.0; 3],
            g0: [0.0; 3],
            iw: t.iw.map(f64::from),
            wx: 0.0,
            wy: 0.0,
            w0: 0.0,
        };
        for k in 0..3 {
            let (i, j) = ((k + 1) % 3, (k + 2) % 3);
            let (ex, ey) = (p[j].0 - p[i].0, p[j].1 - p[i].1);
            // b_k(p) = (ex * (py - yi) - ey * (px - xi)) / area
            pl.gx[k] = -ey * inv;
            pl.gy[k] = ex * inv;
        }
        // At corner 0 (the origin of the planes) the weights are exactly (1, 0, 0).
        pl.g0 = [1.0, 0.0, 0.0];
        for k in 0..3 {
            pl.wx += pl.gx[k] * pl.iw[k];
            pl.wy += pl.gy[k] * pl.iw[k];
            pl.w0 += pl.g0[k] * pl.iw[k];
        }
        pl
    }

    /// 1/w at the centre of sample (ix, iy).
    #[inline(always)]
    pub fn invw(&self, ix: i32, iy: i32) -> f64 {
        let (dx, dy) = (f64::from(ix) + 0.5 - self.ox, f64::from(iy) + 0.5 - self.oy);
        self.wx * dx + self.wy * dy + self.w0
    }

    /// Perspective-correct barycentric coordinates of the corners at sample (ix, iy).
    #[inline(always)]
    pub fn lambdas(&self, ix: i32, iy: i32) -> [f64; 3] {
        let (dx, dy) = (f64::from(ix) + 0.5 - self.ox, f64::from(iy) + 0.5 - self.oy);
        let q = |k: usize| (self.gx[k] * dx + self.gy[k] * dy + self.g0[k]) * self.iw[k];
        let q = [q(0), q(1), q(2)];
        let s = q[0] + q[1] + q[2];
        [q[0] / s, q[1] / s, q[2] / s]
    }
}
