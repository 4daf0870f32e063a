//! Meshes shared by the core's unit tests.

/// Latitude-longitude sphere (poles on +-z), outward counter-clockwise faces.
pub(crate) fn uv_sphere(n_lat: usize, n_lon: usize) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let mut v = vec![[0.0, 0.0, 1.0]];
    for i in 1..n_lat {
        let la = std::f64::consts::PI * i as f64 / n_lat as f64;
        for j in 0..n_lon {
            let lo = 2.0 * std::f64::consts::PI * j as f64 / n_lon as f64;
            v.push([la.sin() * lo.cos(), la.sin() * lo.sin(), la.cos()]);
        }
    }
    v.push([0.0, 0.0, -1.0]);
    let south = (v.len() - 1) as u32;
    let ring = |i: usize, j: usize| (1 + i * n_lon + j % n_lon) as u32;
    let mut f = Vec::new();
    for j in 0..n_lon {
        f.push([0, ring(0, j), ring(0, j + 1)]);
    }
    for i in 0..n_lat - 2 {
        for j in 0..n_lon {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i, j + 1),
                ring(i + 1, j + 1),
                ring(i + 1, j),
            );
            f.push([a, d, c]);
            f.push([a, c, b]);
        }
    }
    for j in 0..n_lon {
        f.push([south, ring(n_lat - 2, j + 1), ring(n_lat - 2, j)]);
    }
    (v, f)
}

/// The faces of a grid of `n` x `n` quads over `(n + 1)^2` vertices numbered row by row (two
/// counter-clockwise triangles a quad).
pub(crate) fn grid_faces(n: usize) -> Vec<[u32; 3]> {
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut f = Vec::new();
    for j in 0..n {
        for i in 0..n {
            f.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            f.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    f
}
