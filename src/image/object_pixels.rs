//! The pixels of one object in a frame's window, gathered in one pass for the `opaque_image`
//! method: its mask, the velocities and depths of its pixels in row order and their mean
//! velocity, the values numpy's `ids[win] == k`, `velocity[win][mask].astype(float64)`,
//! `depth[win][mask]` and `vs.mean(axis=0)` give (the mean as numpy's reduction along the first
//! axis sums it: in float64, pixel after pixel in row order, then divided by the count).

use super::coverage::Window;
use crate::error::{Error, Result};

/// One object's pixels in a window: the mask (`(y1 - y0, x1 - x0)`, row-major), the
/// velocities `(N, 2)` float64 and depths `(N,)` of the masked pixels in row order, and their
/// mean velocity (`[NaN, NaN]` when there is none, as numpy's mean of nothing).
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectPixels {
    /// `ids == k` over the window.
    pub mask: Vec<bool>,
    /// The velocities of the masked pixels, two values each, in row order.
    pub velocity: Vec<f64>,
    /// The depths of the masked pixels, in row order.
    pub depth: Vec<f32>,
    /// The mean of `velocity`.
    pub mean: [f64; 2],
}

/// The pixels of object `k` (`ids == k`) in `window` of a `w` x `h` frame: `ids` `(h, w)`,
/// `velocity` `(h, w, 2)`, `depth` `(h, w)`.
pub fn object_pixels(
    ids: &[i32],
    velocity: &[f32],
    depth: &[f32],
    (w, h): (usize, usize),
    window: Window,
    k: i32,
) -> Result<ObjectPixels> {
    let (y0, y1, x0, x1) = window;
    if ids.len() != w * h || depth.len() != w * h || velocity.len() != w * h * 2 {
        return Err(Error::shape(
            "ids",
            format!("ids and depth ({h},{w}), velocity ({h},{w},2) expected"),
        ));
    }
    if !(y0 <= y1 && y1 <= h && x0 <= x1 && x1 <= w) {
        return Err(Error::value(
            "window",
            format!("({y0}, {y1}, {x0}, {x1}) is not a window of {w}x{h} pixels"),
        ));
    }
    let cols = x1 - x0;
    let mut mask = Vec::with_capacity((y1 - y0) * cols);
    for y in y0..y1 {
        mask.extend(ids[y * w + x0..y * w + x1].iter().map(|&i| i == k));
    }
    let n = mask.iter().filter(|&&m| m).count();
    let (mut vel, mut dep) = (Vec::with_capacity(2 * n), Vec::with_capacity(n));
    let mut sum = [0.0f64; 2];
    for (r, row) in mask.chunks(cols.max(1)).enumerate().take(y1 - y0) {
        let y = y0 + r;
        for (c, _) in row.iter().enumerate().filter(|(_, &m)| m) {
            let j = y * w + x0 + c;
            let v = [velocity[2 * j] as f64, velocity[2 * j + 1] as f64];
            sum[0] += v[0];
            sum[1] += v[1];
            vel.extend(v);
            dep.push(depth[j]);
        }
    }
    let count = n as f64;
    Ok(ObjectPixels {
        mask,
        velocity: vel,
        depth: dep,
        mean: [sum[0] / count, sum[1] / count],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gathers_the_masked_pixels_in_row_order() {
        let (w, h) = (7, 5);
        let ids: Vec<i32> = (0..w * h).map(|i| ((i * 5) % 3) as i32 - 1).collect();
        let velocity: Vec<f32> = (0..w * h * 2).map(|i| i as f32 * 0.5 - 3.0).collect();
        let depth: Vec<f32> = (0..w * h).map(|i| 1.0 + i as f32).collect();
        let win = (1, 4, 2, 6);
        let got = object_pixels(&ids, &velocity, &depth, (w, h), win, 1).unwrap();
        let (mut mask, mut vel, mut dep) = (vec![], vec![], vec![]);
        for y in 1..4 {
            for x in 2..6 {
                let j = y * w + x;
                mask.push(ids[j] == 1);
                if ids[j] == 1 {
                    vel.extend([velocity[2 * j] as f64, velocity[2 * j + 1] as f64]);
                    dep.push(depth[j]);
                }
            }
        }
        assert!(!dep.is_empty());
        let n = dep.len() as f64;
        let sx: f64 = vel.iter().step_by(2).sum();
        let sy: f64 = vel.iter().skip(1).step_by(2).sum();
        assert_eq!(got.mask, mask);
        assert_eq!(got.velocity, vel);
        assert_eq!(got.depth, dep);
        assert_eq!(got.mean, [sx / n, sy / n]);
        let none = object_pixels(&ids, &velocity, &depth, (w, h), win, 7).unwrap();
        assert!(none.depth.is_empty() && none.mean.iter().all(|v| v.is_nan()));
        assert!(object_pixels(&ids, &velocity, &depth, (w, h), (1, 6, 0, 1), 1).is_err());
    }
}
