//! The accumulation buffer's conservative back-face selection: the faces of a rigidly
//! translating mesh that face the eye at some keyframe of the shutter.
//!
//! With a fixed rotation and scale, a face's normal `n` is constant in object space and the eye
//! moves along straight segments between the keyframes' object-space positions `e_k`, so
//! `n . (e - a)` is linear along each segment: a face that faces away at every keyframe faces
//! away throughout and the rasterizer would cull it at every sample. A face is kept when
//! `n . (e_k - a) > -1e-9 |n| |e_k - a|` for some `k` (near edge-on faces are kept).
//!
//! It replaces a numpy expression (cross product, norms, dot products); the two round
//! differently only in the last bits, so they keep different faces only for a face within
//! rounding of the edge-on limit, which the rasterizer would not draw anyway.
//! Faces are handled in chunks whose kept faces are concatenated in order, so the result does not
//! depend on the thread count.
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::mesh::dot;

/// Faces per parallel job.
const CHUNK: usize = 4096;

/// The relative tolerance of the facing test: faces this close to edge-on are kept.
const EDGE_ON: f64 = 1e-9;

#[inline]
fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// Whether the face `(a, b, c)` faces one of the object-space `eyes` (see the module comment).
#[inline]
fn faces_an_eye(a: [f64; 3], b: [f64; 3], c: [f64; 3], eyes: &[[f64; 3]]) -> bool {
    let (u, w) = (sub(b, a), sub(c, a));
    let n = [
        u[1] * w[2] - u[2] * w[1],
        u[2] * w[0] - u[0] * w[2],
        u[0] * w[1] - u[1] * w[0],
    ];
    let limit = -EDGE_ON * dot(n, n).sqrt();
    eyes.iter().any(|&e| {
        let d = sub(e, a);
        dot(n, d) > limit * dot(d, d).sqrt()
    })
}

/// The faces (in their order) of the mesh `vertices`/`faces` that face one of the object-space
/// eye positions `eyes` (K >= 1), conservatively. All three are flat row-major (N,3) arrays
/// (`3 N` values); so is the result. Errors for lengths that are not multiples of 3, non-finite
/// vertices or eyes, no eye, and face indices outside `[0, V)`.
pub fn facing_faces(vertices: &[f64], faces: &[i64], eyes: &[f64]) -> Result<Vec<i64>> {
    for (name, len) in [
        ("vertices", vertices.len()),
        ("faces", faces.len()),
        ("eyes", eyes.len()),
    ] {
        if len % 3 != 0 {
            return Err(Error::shape(name, "expected (N,3) rows"));
        }
    }
    if eyes.is_empty() {
        return Err(Error::shape("eyes", "needs at least one eye position"));
    }
    if eyes.iter().any(|x| !x.is_finite()) {
        return Err(Error::value("eyes", "must be finite"));
    }
    let eyes: Vec<[f64; 3]> = eyes.chunks_exact(3).map(|e| [e[0], e[1], e[2]]).collect();
    let finite = |c: &[f64]| c.iter().all(|x| x.is_finite());
    if !vertices.par_chunks(3 * CHUNK).all(finite) {
        return Err(Error::value("vertices", "must be finite"));
    }
    let nv = (vertices.len() / 3) as i64;
    let in_range = |c: &[i64]| c.iter().all(|&i| (0..nv).contains(&i));
    if !faces.par_chunks(3 * CHUNK).all(in_range) {
        return Err(Error::value(
            "faces",
            format!("indices must be in [0, {nv}) (the vertex count)"),
        ));
    }
    let p = |i: i64| {
        let i = 3 * i as usize;
        [vertices[i], vertices[i + 1], vertices[i + 2]]
    };
    let kept: Vec<Vec<i64>> = faces
        .par_chunks(3 * CHUNK)
        .map(|chunk| {
            let mut out = Vec::new();
            for f in chunk.chunks_exact(3) {
                if faces_an_eye(p(f[0]), p(f[1]), p(f[2]), &eyes) {
                    out.extend_from_slice(f);
                }
            }
            out
        })
        .collect();
    Ok(kept.concat())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::on_threads;

    /// `facing_faces` on row arrays.
    fn facing(v: &[[f64; 3]], f: &[[i64; 3]], eyes: &[[f64; 3]]) -> Result<Vec<[i64; 3]>> {
        let kept = facing_faces(v.as_flattened(), f.as_flattened(), eyes.as_flattened())?;
        Ok(kept.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
    }

    fn grid(n: usize) -> (Vec<[f64; 3]>, Vec<[i64; 3]>) {
        // a bumpy closed-ish sheet: faces of both orientations
        let mut v = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
                v.push([x, y, 0.1 * (7.0 * x).sin() * (5.0 * y).cos()]);
            }
        }
        let f = crate::mesh::grid_faces(n);
        (v, f.iter().map(|t| t.map(i64::from)).collect())
    }

    #[test]
    fn keeps_faces_facing_any_eye_in_order() {
        let (v, f) = grid(40);
        // a height field seen from far above (every face) and far below (none)
        let above = facing(&v, &f, &[[0.5, 0.5, 10.0]]).unwrap();
        let below = facing(&v, &f, &[[0.5, 0.5, -10.0]]).unwrap();
        assert_eq!(above, f);
        assert!(below.is_empty());
        assert_eq!(
            facing(&v, &f, &[[0.5, 0.5, -10.0], [0.5, 0.5, 10.0]]).unwrap(),
            f
        );
        // from just above the bumps, some faces turn away; the kept ones keep their order
        let low = facing(&v, &f, &[[0.5, 0.5, 0.02]]).unwrap();
        assert!(!low.is_empty() && low.len() < f.len());
        let pos: Vec<usize> = low
            .iter()
            .map(|x| f.iter().position(|y| y == x).unwrap())
            .collect();
        assert!(pos.windows(2).all(|w| w[0] < w[1]));
    }

    #[test]
    fn thread_count_independent() {
        let (v, f) = grid(120);
        let eyes = [[0.3, 0.2, 2.0], [0.9, 0.4, 1.5]];
        let one = on_threads(1, || facing(&v, &f, &eyes).unwrap());
        let two = on_threads(2, || facing(&v, &f, &eyes).unwrap());
        assert_eq!(one, two);
    }

    #[test]
    fn rejects_bad_input() {
        let (v, f) = grid(2);
        assert!(facing(&v, &f, &[]).is_err());
        assert!(facing_faces(&[0.0; 4], &[0; 3], &[0.0; 3]).is_err());
        assert!(facing_faces(&[0.0; 9], &[0; 4], &[0.0; 3]).is_err());
        assert!(facing_faces(&[0.0; 9], &[0; 3], &[0.0; 4]).is_err());
        assert!(facing(&v, &f, &[[f64::NAN, 0.0, 0.0]]).is_err());
        let mut bad = f.clone();
        bad[0][1] = v.len() as i64;
        assert!(facing(&v, &bad, &[[0.0, 0.0, 1.0]]).is_err());
        bad[0][1] = -1;
        assert!(facing(&v, &bad, &[[0.0, 0.0, 1.0]]).is_err());
        let mut nan = v.clone();
        nan[0][2] = f64::INFINITY;
        assert!(facing(&nan, &f, &[[0.0, 0.0, 1.0]]).is_err());
    }
}
