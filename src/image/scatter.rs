//! Splatting sharp renders along their pixels' image paths, the paths made on the fly: the
//! kernel of the motion volume's per-pixel colours (`motionblur.methods._volume_colors`).
//!
//! Each [`Piece`] is a sharp render (a window of the camera's image) of the moving objects at
//! the middle of a piece of the shutter, with its colour, depth and object id per pixel. Every
//! covered pixel is carried back to its camera-space point by its depth, then through its
//! object's `points` maps (one 4x4 per path time, taking that point to homogeneous output pixel
//! coordinates) to the polyline its image follows during the piece, and splatted along it with
//! [`super::splat`]'s segments. Nothing per source is materialised: the same sums as building
//! every path and calling `splat_paths`, without the arrays.
use rayon::prelude::*;

use super::splat::{sum_buffers, trace, trace_straight, MAX_PATH_POINTS};
use crate::error::{Error, Result};
use crate::frame::Layer;

/// Largest image accepted (pixels), output or piece, as for the rasterizer.
const MAX_PIXELS: usize = 1 << 25;

/// Most sources per run: the sources are cut into runs of this size (at most [`RUNS`] runs,
/// longer ones then), each splatted into its own buffer, the buffers summed in run order: the
/// same sums for any thread count.
const RUN_SOURCES: usize = 1024;
const RUNS: usize = 8;

/// One sharp render of the movers and how its pixels move.
#[derive(Clone, Copy)]
pub struct Piece<'a> {
    /// The render: premultiplied colours, depth along the view axis (positive in front of the
    /// camera) and object id per pixel.
    pub layer: Layer<'a>,
    /// The camera-space point of pixel `(i, j)` at depth `z` is
    /// `z (ray[0] (i + 0.5) + ray[1], ray[2] (j + 0.5) + ray[3], -1)`.
    pub ray: [f64; 4],
    /// Every colour is multiplied by this (the piece's share of the shutter).
    pub weight: f32,
    /// Ids of the objects that move (pixels of other ids, or uncovered ones, are no sources).
    pub objects: &'a [i32],
    /// Per object, `points` row-major 4x4 maps from the camera-space point to homogeneous
    /// output pixel coordinates `(x w, y w, ., w)` at each path time (`w > 1e-9`: in front).
    pub maps: &'a [f64],
}

/// A path is splatted as one segment from its first to its last point, cut at its inner points
/// (see `splat::trace_straight`), when every point lies within this many pixels of the uniform
/// motion between them (a translation without perspective change of speed).
pub const STRAIGHT_TOLERANCE: f32 = 1e-3;

/// Whether `path` (3 points or more, all finite) is a uniform straight motion up to
/// [`STRAIGHT_TOLERANCE`] whose segments all have the whole path's major axis and are longer
/// than a point splat's 1e-6 along it (so that splatting it whole changes only the rounding).
fn straight(path: &[[f32; 2]]) -> bool {
    let n = path.len();
    if n < 3 {
        return false;
    }
    let (a, b) = (path[0], path[n - 1]);
    if !(a.iter().chain(&b).all(|v| v.is_finite())) {
        return false;
    }
    let d = [b[0] - a[0], b[1] - a[1]];
    let k = usize::from(d[1].abs() > d[0].abs());
    let step = 1.0 / (n - 1) as f32;
    let on_line = path[1..n - 1].iter().enumerate().all(|(s, p)| {
        let u = (s + 1) as f32 * step;
        (0..2).all(|k| (p[k] - (a[k] + u * (b[k] - a[k]))).abs() <= STRAIGHT_TOLERANCE)
    });
    on_line
        && path.windows(2).all(|s| {
            let e = [s[1][0] - s[0][0], s[1][1] - s[0][1]];
            usize::from(e[1].abs() > e[0].abs()) == k && e[k].abs() >= 1e-6
        })
}

fn check_piece(k: usize, p: &Piece, points: usize) -> Result<()> {
    let n = p.layer.width.saturating_mul(p.layer.height);
    if n == 0 || n > MAX_PIXELS {
        return Err(Error::value(
            "pieces",
            format!(
                "piece {k}: expected 1..={MAX_PIXELS} pixels, got {}x{}",
                p.layer.width, p.layer.height
            ),
        ));
    }
    let bad = |name: &'static str, want: usize, got: usize| {
        Error::shape(
            name,
            format!("piece {k}: expected {want} values, got {got}"),
        )
    };
    if p.layer.rgba.len() != 4 * n {
        return Err(bad("rgba", 4 * n, p.layer.rgba.len()));
    }
    if p.layer.depth.len() != n {
        return Err(bad("depth", n, p.layer.depth.len()));
    }
    if p.layer.ids.len() != n {
        return Err(bad("ids", n, p.layer.ids.len()));
    }
    if p.maps.len() != p.objects.len() * points * 16 {
        return Err(bad("maps", p.objects.len() * points * 16, p.maps.len()));
    }
    if !p.ray.iter().all(|v| v.is_finite()) {
        return Err(Error::value("ray", format!("piece {k}: must be finite")));
    }
    if !(p.weight.is_finite() && p.weight >= 0.0) {
        return Err(Error::value(
            "weight",
            format!("piece {k}: must be finite and >= 0, got {}", p.weight),
        ));
    }
    if !p.maps.iter().all(|v| v.is_finite()) {
        return Err(Error::value(
            "maps",
            format!("piece {k}: contains NaN or inf"),
        ));
    }
    Ok(())
}

/// The sources of `piece` (number `k`): `(piece, pixel, object slot)` of every pixel with
/// alpha > 0 whose id is among the piece's objects, in row-major order.
fn sources(k: usize, piece: &Piece, out: &mut Vec<[u32; 3]>) -> Result<()> {
    let mut slots: Vec<(i32, u32)> = piece
        .objects
        .iter()
        .enumerate()
        .map(|(s, &id)| (id, s as u32))
        .collect();
    slots.sort_by_key(|&(id, s)| (id, s));
    slots.dedup_by_key(|v| v.0); // the first slot of a repeated id
    for (px, c) in piece.layer.rgba.chunks_exact(4).enumerate() {
        if c[3].is_nan() || c[3] <= 0.0 {
            continue;
        }
        if !c.iter().all(|v| v.is_finite()) {
            return Err(Error::value(
                "rgba",
                format!("piece {k}: contains NaN or inf"),
            ));
        }
        if let Ok(at) = slots.binary_search_by_key(&piece.layer.ids[px], |v| v.0) {
            out.push([k as u32, px as u32, slots[at].1]);
        }
    }
    Ok(())
}

/// The time average (`height`, `width`, 4) of the pieces' pixels splatted along their paths of
/// `points` points each (the shutter split equally among the `points - 1` segments; one point:
/// still), row-major; see the module doc. Path points behind the camera drop their segments, as
/// do the parts of the paths outside the image.
pub fn scatter_pieces(
    width: usize,
    height: usize,
    pieces: &[Piece],
    points: usize,
) -> Result<Vec<f32>> {
    if width == 0 || height == 0 || width.saturating_mul(height) > MAX_PIXELS {
        return Err(Error::value(
            "size",
            format!("expected 1..={MAX_PIXELS} pixels, got {width}x{height}"),
        ));
    }
    if points == 0 || points > MAX_PATH_POINTS {
        return Err(Error::value(
            "points",
            format!("expected 1..={MAX_PATH_POINTS} points per path, got {points}"),
        ));
    }
    if pieces.len() > u32::MAX as usize {
        return Err(Error::value("pieces", "too many"));
    }
    let mut src = Vec::new();
    for (k, p) in pieces.iter().enumerate() {
        check_piece(k, p, points)?;
        sources(k, p, &mut src)?;
    }
    let n = src.len();
    let runs = n.div_ceil(RUN_SOURCES).clamp(1, RUNS);
    let run = n.div_ceil(runs).max(1);
    super::check_splat_buffers("scatter_pieces", width, height, n.div_ceil(run))?;
    let buffers: Vec<Vec<[f32; 4]>> = src
        .par_chunks(run)
        .map(|chunk| {
            let mut out = vec![[0.0f32; 4]; width * height];
            let mut path = [[0.0f32; 2]; MAX_PATH_POINTS];
            for &[k, px, slot] in chunk {
                let p = &pieces[k as usize];
                let px = px as usize;
                let c = &p.layer.rgba[4 * px..4 * px + 4];
                let c = [c[0], c[1], c[2], c[3]].map(|v| v * p.weight);
                let z = p.layer.depth[px] as f64;
                let (i, j) = (
                    (px % p.layer.width) as f64 + 0.5,
                    (px / p.layer.width) as f64 + 0.5,
                );
                let q = [
                    z * (p.ray[0] * i + p.ray[1]),
                    z * (p.ray[2] * j + p.ray[3]),
                    -z,
                ];
                let maps = &p.maps[slot as usize * points * 16..][..points * 16];
                for (pt, m) in path.iter_mut().zip(maps.chunks_exact(16)) {
                    let row = |r: usize| {
                        m[4 * r] * q[0] + m[4 * r + 1] * q[1] + m[4 * r + 2] * q[2] + m[4 * r + 3]
                    };
                    let wc = row(3);
                    *pt = if wc > 1e-9 {
                        [(row(0) / wc) as f32, (row(1) / wc) as f32]
                    } else {
                        [f32::NAN; 2]
                    };
                }
                let path = &path[..points];
                if straight(path) {
                    trace_straight(&mut out, width, height, c, path);
                } else {
                    trace(&mut out, width, height, c, path);
                }
            }
            out
        })
        .collect();
    Ok(sum_buffers(buffers, width * height))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::splat_paths;

    /// A 6x5 piece, pixels (1..4, 1..3) covered by object 7, the rest empty; ray of a 90 degree
    /// camera over a 6x5 image; maps: the identity camera moving `dx` pixels per point.
    fn piece_data() -> (Vec<f32>, Vec<f32>, Vec<i32>) {
        let (w, h) = (6, 5);
        let mut rgba = vec![0.0f32; 4 * w * h];
        let mut ids = vec![-1i32; w * h];
        for j in 1..3 {
            for i in 1..4 {
                let px = j * w + i;
                rgba[4 * px..4 * px + 4].copy_from_slice(&[
                    0.1 * i as f32,
                    0.2,
                    0.05 * j as f32,
                    0.9,
                ]);
                ids[px] = 7;
            }
        }
        (rgba, vec![2.0f32; w * h], ids)
    }

    /// Maps taking camera point q to pixel (q.x / -q.z * 3 + 3 + dx s, -q.y / -q.z * 2.5 + 2.5).
    fn maps(points: usize, dx: f64) -> Vec<f64> {
        (0..points)
            .flat_map(|s| {
                let sh = dx * s as f64;
                [
                    3.0,
                    0.0,
                    -(3.0 + sh),
                    0.0, //
                    0.0,
                    -2.5,
                    -2.5,
                    0.0, //
                    0.0,
                    0.0,
                    1.0,
                    0.0, //
                    0.0,
                    0.0,
                    -1.0,
                    0.0,
                ]
            })
            .collect()
    }

    #[test]
    fn matches_explicit_paths_and_threads_do_not_matter() {
        let (rgba, depth, ids) = piece_data();
        let points = 3;
        let m = maps(points, 1.5);
        // ray: x = (i + 0.5) / 6 * 2 - 1, y = 1 - (j + 0.5) / 5 * 2 (a 90 degree square-ish camera)
        let piece = Piece {
            layer: Layer {
                rgba: &rgba,
                depth: &depth,
                ids: &ids,
                width: 6,
                height: 5,
            },
            ray: [2.0 / 6.0, -1.0, -2.0 / 5.0, 1.0],
            weight: 0.5,
            objects: &[3, 7],
            maps: &[m.clone(), m.clone()].concat(),
        };
        let one = crate::on_threads(1, || scatter_pieces(9, 6, &[piece], points).unwrap());
        let two = crate::on_threads(2, || scatter_pieces(9, 6, &[piece], points).unwrap());
        assert_eq!(one, two);
        // the same sources by hand
        let (mut colors, mut paths) = (Vec::new(), Vec::new());
        for j in 1..3 {
            for i in 1..4 {
                let px = j * 6 + i;
                let c = &rgba[4 * px..4 * px + 4];
                colors.push([c[0], c[1], c[2], c[3]].map(|v| v * 0.5));
                for s in 0..points {
                    // the camera point's own pixel, shifted 1.5 s
                    paths.push([(i as f32 + 0.5) + 1.5 * s as f32, j as f32 + 0.5]);
                }
            }
        }
        let want = splat_paths(9, 6, &colors, &paths, points).unwrap();
        for (a, b) in one.iter().zip(&want) {
            assert!((a - b).abs() < 1e-5, "{a} {b}");
        }
        let total: f32 = one.iter().skip(3).step_by(4).sum();
        assert!((total - 6.0 * 0.9 * 0.5).abs() < 1e-4, "{total}");
    }

    #[test]
    fn bad_input_is_an_error() {
        let (rgba, depth, ids) = piece_data();
        let m = maps(2, 1.0);
        let good = || Piece {
            layer: Layer {
                rgba: &rgba,
                depth: &depth,
                ids: &ids,
                width: 6,
                height: 5,
            },
            ray: [0.3, -1.0, -0.4, 1.0],
            weight: 1.0,
            objects: &[7],
            maps: &m,
        };
        assert!(scatter_pieces(9, 6, &[good()], 2).is_ok());
        assert!(scatter_pieces(0, 6, &[good()], 2).is_err());
        assert!(scatter_pieces(9, 6, &[good()], 3).is_err()); // maps of 2 points
        assert!(scatter_pieces(9, 6, &[good()], 0).is_err());
        assert!(scatter_pieces(
            9,
            6,
            &[Piece {
                layer: Layer {
                    width: 5,
                    ..good().layer
                },
                ..good()
            }],
            2
        )
        .is_err());
        assert!(scatter_pieces(
            9,
            6,
            &[Piece {
                weight: f32::NAN,
                ..good()
            }],
            2
        )
        .is_err());
        let nan = vec![f64::NAN; 32];
        assert!(scatter_pieces(
            9,
            6,
            &[Piece {
                maps: &nan,
                ..good()
            }],
            2
        )
        .is_err());
        let mut bad = rgba.clone();
        bad[4 * 7] = f32::INFINITY;
        assert!(scatter_pieces(
            9,
            6,
            &[Piece {
                layer: Layer {
                    rgba: &bad,
                    ..good().layer
                },
                ..good()
            }],
            2
        )
        .is_err());
        // no pieces, or nothing covered: an empty image
        let out = scatter_pieces(9, 6, &[], 2).unwrap();
        assert!(out.iter().all(|v| *v == 0.0) && out.len() == 9 * 6 * 4);
    }
}
