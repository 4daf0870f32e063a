//! Homogeneous clipping of triangles against the near and far planes and a guard band.
//!
//! Triangles that cross the near plane or lie partly behind the camera are clipped in clip
//! space (never dropped, never wrapped through infinity). In x and y only a wide guard band is
//! clipped: it keeps the fixed-point screen coordinates in range while triangles that merely
//! leave the viewport go through untouched.
//!
//! Watertightness: the intersection of an edge with a plane is always computed from the edge's
//! inside end towards its outside end, so two triangles sharing an edge create bit-identical new
//! vertices on it, whatever the direction in which each one walks the edge.

/// A clip-space position and its barycentric coordinates in the original triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClipVertex {
    pub pos: [f64; 4],
    pub bary: [f64; 3],
}

/// The most vertices a triangle clipped by six planes can have.
pub const MAX_POLY: usize = 9;

/// The near plane's bit in an outcode (bits: near, far, left, right, bottom, top).
#[cfg(test)]
const NEAR: u8 = 1;

/// The clip volume: the near/far planes of OpenGL (-w <= z <= w) and a guard band in x and y
/// (|x| <= gx w, |y| <= gy w).
#[derive(Clone, Copy, Debug)]
pub struct ClipVolume {
    pub gx: f64,
    pub gy: f64,
}

#[inline]
fn distance(p: &[f64; 4], plane: usize, gx: f64, gy: f64) -> f64 {
    let [x, y, z, w] = *p;
    match plane {
        0 => z + w,
        1 => w - z,
        2 => x + gx * w,
        3 => gx * w - x,
        4 => y + gy * w,
        _ => gy * w - y,
    }
}

/// Outcode of a point against the planes with the given band (1 = the viewport itself).
#[inline]
pub fn outcode(p: &[f64; 4], gx: f64, gy: f64) -> u8 {
    let mut c = 0u8;
    for plane in 0..6 {
        // `!(d >= 0)` also flags NaN as outside.
        if !(distance(p, plane, gx, gy) >= 0.0) {
            c |= 1 << plane;
        }
    }
    c
}

impl ClipVolume {
    /// Guard band factors for an internal image of `ws` x `hs` samples: screen coordinates stay
    /// within +-2^16 samples, so 8-bit fixed point fits in i32 and edge products in i64.
    pub fn for_size(ws: u32, hs: u32) -> Self {
        let band = |s: u32| ((131072.0 / f64::from(s)) - 2.0).max(1.0);
        ClipVolume {
            gx: band(ws),
            gy: band(hs),
        }
    }

    /// Clips the triangle `tri` (clip-space positions) against the planes flagged in `planes`.
    /// Returns the number of polygon vertices written to `out` (0 when nothing is left).
    pub fn clip(&self, tri: [[f64; 4]; 3], planes: u8, out: &mut [ClipVertex; MAX_POLY]) -> usize {
        let mut a = [ClipVertex {
            pos: [0.0; 4],
            bary: [0.0; 3],
        }; MAX_POLY];
        let mut n = 3;
        for (k, p) in tri.iter().enumerate() {
            let mut bary = [0.0; 3];
            bary[k] = 1.0;
            a[k] = ClipVertex { pos: *p, bary };
        }
        for plane in 0..6 {
            if planes & (1 << plane) == 0 {
                continue;
            }
            let mut m = 0;
            let mut b = [a[0]; MAX_POLY];
            for i in 0..n {
                let cur = a[i];
                let next = a[(i + 1) % n];
                let dc = distance(&cur.pos, plane, self.gx, self.gy);
                let dn = distance(&next.pos, plane, self.gx, self.gy);
                let cin = dc >= 0.0;
                let nin = dn >= 0.0;
                if cin && m < MAX_POLY {
                    b[m] = cur;
                    m += 1;
                }
                if cin != nin && m < MAX_POLY {
                    // From the inside end towards the outside end: canonical for shared edges.
                    let (inside, outside, di, dout) = if cin {
                        (cur, next, dc, dn)
                    } else {
                        (next, cur, dn, dc)
                    };
                    let t = di / (di - dout);
                    let mut v = inside;
                    for c in 0..4 {
                        v.pos[c] = inside.pos[c] + t * (outside.pos[c] - inside.pos[c]);
                    }
                    for c in 0..3 {
                        v.bary[c] = inside.bary[c] + t * (outside.bary[c] - inside.bary[c]);
                    }
                    b[m] = v;
                    m += 1;
                }
            }
            n = m;
            a = b;
            if n < 3 {
                return 0;
            }
        }
        out[..n].copy_from_slice(&a[..n]);
        n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_triangle_crossing_the_near_plane_becomes_a_quad_in_front_of_it() {
        let vol = ClipVolume { gx: 4.0, gy: 4.0 };
        // One vertex behind the near plane (z < -w).
        let tri = [
            [0.0, 0.0, -2.0, 1.0],
            [1.0, 0.0, 0.5, 1.0],
            [0.0, 1.0, 0.5, 1.0],
        ];
        let mut out = [ClipVertex {
            pos: [0.0; 4],
            bary: [0.0; 3],
        }; MAX_POLY];
        let n = vol.clip(tri, outcode(&tri[0], 4.0, 4.0), &mut out);
        assert_eq!(n, 4);
        for v in &out[..n] {
            assert!(v.pos[2] + v.pos[3] >= -1e-12);
            let s: f64 = v.bary.iter().sum();
            assert!((s - 1.0).abs() < 1e-12);
            // The position is the barycentric mix of the corners.
            for c in 0..4 {
                let want: f64 = (0..3).map(|k| v.bary[k] * tri[k][c]).sum();
                assert!((want - v.pos[c]).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn shared_edges_clip_to_identical_vertices() {
        let vol = ClipVolume { gx: 1.0, gy: 1.0 };
        let p = [0.3, 0.1, -3.0, 1.0];
        let q = [0.7, -0.2, 0.4, 1.3];
        let r = [0.2, 0.9, 0.2, 2.0];
        let s = [-0.5, -0.6, 0.1, 1.0];
        let mut o1 = [ClipVertex {
            pos: [0.0; 4],
            bary: [0.0; 3],
        }; MAX_POLY];
        let mut o2 = o1;
        let n1 = vol.clip([p, q, r], NEAR, &mut o1);
        let n2 = vol.clip([q, p, s], NEAR, &mut o2);
        let on_pq = |o: &[ClipVertex]| {
            o.iter()
                .map(|v| v.pos)
                .filter(|x| x != &q && x != &r && x != &s && x != &p)
                .collect::<Vec<_>>()
        };
        let a = on_pq(&o1[..n1]);
        let b = on_pq(&o2[..n2]);
        assert!(a.iter().any(|x| b.contains(x)), "{a:?} vs {b:?}");
    }

    #[test]
    fn a_triangle_behind_the_camera_vanishes() {
        let vol = ClipVolume { gx: 4.0, gy: 4.0 };
        let tri = [
            [0.0, 0.0, -2.0, -1.0],
            [1.0, 0.0, -2.0, -1.0],
            [0.0, 1.0, -2.0, -1.0],
        ];
        let mut out = [ClipVertex {
            pos: [0.0; 4],
            bary: [0.0; 3],
        }; MAX_POLY];
        assert_eq!(vol.clip(tri, 0b11, &mut out), 0);
    }
}
