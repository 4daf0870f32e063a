//! Uniform conforming subdivision of meshes, for alphas that must follow a profile finer than
//! a coarse mesh (the coverage filters of `coverage.rs`, the spin of `spin.rs`).
use rayon::prelude::*;

use super::types::{Colors, VolumeOptions};
use crate::error::Result;
use crate::mesh::{dot, Mesh};
use crate::motion::Path;

/// A new vertex of a subdivided mesh: the weights of three original vertices.
pub type Blend = ([u32; 3], [f64; 3]);

/// The result of [`subdivide`].
pub struct Subdivision {
    pub vertices: Vec<[f64; 3]>,
    pub faces: Vec<[u32; 3]>,
    /// Per new vertex, its blend of original vertices.
    pub blend: Vec<Blend>,
    /// Per new face, the original face it lies in.
    pub parent: Vec<u32>,
}

/// Uniform conforming subdivision: every edge into `s` parts, every face into `s * s` faces in
/// the same orientation. Points on a shared edge are computed once from its lower-index end, so
/// a closed mesh stays closed. Returns vertices (the originals first, in order), faces and each
/// vertex's blend of original vertices (for colours and normals).
pub fn subdivide(vertices: &[[f64; 3]], faces: &[[u32; 3]], s: usize) -> Subdivision {
    let mut out_v = vertices.to_vec();
    let mut blend: Vec<Blend> = (0..vertices.len() as u32)
        .map(|v| ([v, v, v], [1.0, 0.0, 0.0]))
        .collect();
    let mut out_f = Vec::with_capacity(faces.len() * s * s);
    let mut parent = Vec::with_capacity(faces.len() * s * s);
    let mut edge_points: std::collections::HashMap<(u32, u32, usize), u32> =
        std::collections::HashMap::new();
    let lerp = |p: [f64; 3], q: [f64; 3], t: f64| {
        [
            p[0] + (q[0] - p[0]) * t,
            p[1] + (q[1] - p[1]) * t,
            p[2] + (q[2] - p[2]) * t,
        ]
    };
    let mut grid = vec![0u32; (s + 1) * (s + 1)];
    for (fi, &[a, b, c]) in faces.iter().enumerate() {
        let (pa, pb, pc) = (
            vertices[a as usize],
            vertices[b as usize],
            vertices[c as usize],
        );
        for j in 0..=s {
            for i in 0..=(s - j) {
                let k = s - i - j;
                // (i, j): weight i/s on b, j/s on c, k/s on a.
                let on_edge = |p: u32, q: u32, steps: usize| -> (u32, u32, usize) {
                    if p < q {
                        (p, q, steps)
                    } else {
                        (q, p, s - steps)
                    }
                };
                let key = if (i == 0 && j == 0) || i == s || j == s {
                    None
                } else if j == 0 {
                    Some(on_edge(a, b, i))
                } else if i == 0 {
                    Some(on_edge(a, c, j))
                } else if k == 0 {
                    Some(on_edge(b, c, j))
                } else {
                    Some((u32::MAX, u32::MAX, 0))
                };
                let id = match key {
                    None => [a, b, c][if i == s {
                        1
                    } else if j == s {
                        2
                    } else {
                        0
                    }],
                    Some((u32::MAX, _, _)) => {
                        let w = [
                            k as f64 / s as f64,
                            i as f64 / s as f64,
                            j as f64 / s as f64,
                        ];
                        out_v.push([
                            w[0] * pa[0] + w[1] * pb[0] + w[2] * pc[0],
                            w[0] * pa[1] + w[1] * pb[1] + w[2] * pc[1],
                            w[0] * pa[2] + w[1] * pb[2] + w[2] * pc[2],
                        ]);
                        blend.push(([a, b, c], w));
                        (out_v.len() - 1) as u32
                    }
                    Some((p, q, st)) => *edge_points.entry((p, q, st)).or_insert_with(|| {
                        let t = st as f64 / s as f64;
                        out_v.push(lerp(vertices[p as usize], vertices[q as usize], t));
                        blend.push(([p, q, q], [1.0 - t, t, 0.0]));
                        (out_v.len() - 1) as u32
                    }),
                };
                grid[j * (s + 1) + i] = id;
            }
        }
        let g = |i: usize, j: usize| grid[j * (s + 1) + i];
        for j in 0..s {
            for i in 0..(s - j) {
                out_f.push([g(i, j), g(i + 1, j), g(i, j + 1)]);
                parent.push(fi as u32);
                if i + j + 1 < s {
                    out_f.push([g(i + 1, j), g(i + 1, j + 1), g(i, j + 1)]);
                    parent.push(fi as u32);
                }
            }
        }
    }
    Subdivision {
        vertices: out_v,
        faces: out_f,
        blend,
        parent,
    }
}

/// Largest number of faces a coverage-filter subdivision may produce.
const MAX_SUBDIVIDED_FACES: usize = 1 << 20;

/// How finely to cut a coarse mesh so that per-vertex coverage alphas can follow the coverage
/// profile along the motion, which changes over `min(path length, extent)`: every edge (world
/// units, at shutter open) is cut to at most `max(min(L, E) / 2, E / 8)`, in 1..=8 parts, and
/// the result stays under [`MAX_SUBDIVIDED_FACES`].
pub(crate) fn subdivision_factor(mesh: &Mesh, path: &Path, length: f64, extent: f64) -> usize {
    subdivision_for_edge(mesh, path, (0.25 * length.min(extent)).max(extent / 16.0))
}

/// The number of parts (1..=16, within [`MAX_SUBDIVIDED_FACES`]) that cuts every edge of the
/// mesh placed by the first keyframe to at most `h` (world units).
pub(crate) fn subdivision_for_edge(mesh: &Mesh, path: &Path, h: f64) -> usize {
    let faces = mesh.faces();
    if h.is_nan() || h <= 0.0 || faces.len() * 4 > MAX_SUBDIVIDED_FACES {
        return 1;
    }
    let v = mesh.vertices();
    let f0 = &path.frames[0];
    // Without a rotation or scale the edges keep their object-space lengths (the same values).
    let longest = if f0.has_identity_linear() {
        mesh.longest_edge()
    } else {
        faces
            .par_iter()
            .map(|f| {
                (0..3)
                    .map(|k| {
                        let (a, b) = (v[f[k] as usize], v[f[(k + 1) % 3] as usize]);
                        let d = f0.vector([b[0] - a[0], b[1] - a[1], b[2] - a[2]]);
                        dot(d, d).sqrt()
                    })
                    .fold(0.0, f64::max)
            })
            .reduce(|| 0.0, f64::max)
    };
    let by_budget = ((MAX_SUBDIVIDED_FACES / faces.len()) as f64).sqrt().floor() as usize;
    ((longest / h).ceil() as usize)
        .clamp(1, 16)
        .min(by_budget.max(1))
}

/// The mesh cut `s` times along every edge, with colours and normals blended to the new vertices.
pub(crate) fn subdivided(
    mesh: &Mesh,
    opts: &VolumeOptions,
    s: usize,
) -> Result<(Mesh, VolumeOptions, Vec<u32>)> {
    let Subdivision {
        vertices: sv,
        faces: sf,
        blend,
        parent,
    } = subdivide(mesh.vertices(), mesh.faces(), s);
    let normals = opts
        .normals
        .as_deref()
        .unwrap_or_else(|| mesh.cached_vertex_normals());
    let mix3 = |(ids, w): &([u32; 3], [f64; 3])| {
        let mut o = [0.0; 3];
        for (i, wi) in ids.iter().zip(w) {
            for (x, y) in o.iter_mut().zip(normals[*i as usize]) {
                *x += wi * y;
            }
        }
        o
    };
    let colors = match &opts.colors {
        Colors::Uniform(c) => Colors::Uniform(*c),
        Colors::PerFace(c) => Colors::PerFace(parent.iter().map(|&p| c[p as usize]).collect()),
        Colors::PerVertex(c) => Colors::PerVertex(
            blend
                .iter()
                .map(|(ids, w)| {
                    let mut o = [0.0f32; 4];
                    for (i, wi) in ids.iter().zip(w) {
                        for (x, y) in o.iter_mut().zip(c[*i as usize]) {
                            *x += *wi as f32 * y;
                        }
                    }
                    o
                })
                .collect(),
        ),
    };
    let out = VolumeOptions {
        filter: opts.filter,
        colors,
        normals: Some(blend.par_iter().map(mix3).collect()),
        camera: opts.camera,
        contour_line: opts.contour_line,
        visible_only: opts.visible_only,
        contours: opts.contours.clone(),
        window: opts.window,
    };
    Ok((Mesh::new(sv, sf)?, out, parent))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn subdivision_is_conforming_and_keeps_the_area() {
        let v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let f = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let Subdivision {
            vertices: sv,
            faces: sf,
            blend,
            parent,
        } = subdivide(&v, &f, 3);
        assert_eq!(sf.len(), 4 * 9);
        assert_eq!(parent.len(), sf.len());
        assert_eq!(parent[9], 1);
        // 4 corners + 6 edges * 2 + 4 faces * 1 interior point.
        assert_eq!(sv.len(), 4 + 12 + 4);
        assert_eq!(blend.len(), sv.len());
        let mesh = crate::mesh::Mesh::new(sv, sf).unwrap();
        assert!(mesh.stats().is_closed());
        let area = |m: &crate::mesh::Mesh| {
            m.face_normals_raw()
                .iter()
                .map(|n| dot(*n, *n).sqrt())
                .sum::<f64>()
        };
        let orig = crate::mesh::Mesh::new(v, f).unwrap();
        assert!((area(&mesh) - area(&orig)).abs() < 1e-12);
    }
}
