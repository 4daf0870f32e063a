//! Vector helpers in the numpy twins' order of operations, the mesh's face and vertex normals
//! and its face planes.
use rayon::prelude::*;

/// `(b - a) x (c - a)`, evaluated exactly as numpy's `np.cross(b - a, c - a)` in the vertices'
/// own precision (f64 for meshes, f32 for the blur shell's snapshots).
#[inline]
pub fn face_normal<T>(v: &[[T; 3]], f: &[u32; 3]) -> [T; 3]
where
    T: Copy + std::ops::Sub<Output = T> + std::ops::Mul<Output = T>,
{
    let a = v[f[0] as usize];
    let b = v[f[1] as usize];
    let c = v[f[2] as usize];
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let w = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    [
        u[1] * w[2] - u[2] * w[1],
        u[2] * w[0] - u[0] * w[2],
        u[0] * w[1] - u[1] * w[0],
    ]
}

/// `x0*y0 + x1*y1 + x2*y2`, left to right (no fused multiply-add), as the numpy twin computes it.
#[inline]
pub fn dot(x: [f64; 3], y: [f64; 3]) -> f64 {
    x[0] * y[0] + x[1] * y[1] + x[2] * y[2]
}

/// `n / |n|`, or zero when `|n|` is zero or not finite.
#[inline]
pub fn normalize(n: [f64; 3]) -> [f64; 3] {
    let l = dot(n, n).sqrt();
    if l > 0.0 && l.is_finite() {
        [n[0] / l, n[1] / l, n[2] / l]
    } else {
        [0.0; 3]
    }
}

/// Unnormalised face normals `(b - a) x (c - a)` (twice the area), in vertex units squared.
pub fn face_normals_raw(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> Vec<[f64; 3]> {
    faces.par_iter().map(|f| face_normal(vertices, f)).collect()
}

/// Unit face normals; degenerate faces get `[0, 0, 0]`.
pub fn face_normals(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> Vec<[f64; 3]> {
    faces
        .par_iter()
        .map(|f| normalize(face_normal(vertices, f)))
        .collect()
}

/// Area-weighted vertex normals (sum of the raw normals of the faces around the vertex),
/// normalised; a vertex with no non-degenerate face gets `[0, 0, 0]`.
pub fn vertex_normals(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> Vec<[f64; 3]> {
    let mut acc = vec![[0.0f64; 3]; vertices.len()];
    for f in faces {
        let n = face_normal(vertices, f);
        for &i in f {
            let a = &mut acc[i as usize];
            a[0] += n[0];
            a[1] += n[1];
            a[2] += n[2];
        }
    }
    acc.into_par_iter().map(normalize).collect()
}

/// A face whose sine at its first corner is below this is a sliver (or degenerate): its plane
/// in [`FacePlanes`] has a NaN offset, so the motion volume's rim selection always examines it.
pub const SLIVER: f64 = 1e-2;

/// Per-face planes of a mesh in object space (cached by [`Mesh::face_planes`]).
#[derive(Debug, Clone)]
pub struct FacePlanes {
    planes: Vec<[f32; 4]>,
    /// The mean of the vertices.
    pub center: [f64; 3],
    /// The largest distance of a vertex from `center`.
    pub radius: f64,
}

impl FacePlanes {
    /// The planes of `faces` over `vertices` (scene units).
    pub fn new(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> Self {
        let k = vertices.len() as f64;
        let s = vertices
            .iter()
            .fold([0.0; 3], |a, v| [a[0] + v[0], a[1] + v[1], a[2] + v[2]]);
        let center = [s[0] / k, s[1] / k, s[2] / k];
        let sub = |p: [f64; 3], q: [f64; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
        let len = |p: [f64; 3]| dot(p, p).sqrt();
        let radius = vertices
            .par_iter()
            .map(|v| len(sub(*v, center)))
            .reduce(|| 0.0, f64::max);
        let planes = faces
            .par_iter()
            .with_min_len(4096)
            .map(|f| {
                let a = vertices[f[0] as usize];
                let n = face_normal(vertices, f);
                let (u, w) = (
                    sub(vertices[f[1] as usize], a),
                    sub(vertices[f[2] as usize], a),
                );
                let nn = len(n);
                let solid = nn > 0.0 && nn >= SLIVER * len(u) * len(w);
                if !solid {
                    return [0.0, 0.0, 0.0, f32::NAN];
                }
                let m = n.map(|x| x / nn);
                let off = dot(m, sub(a, center));
                [m[0] as f32, m[1] as f32, m[2] as f32, off as f32]
            })
            .collect();
        FacePlanes {
            planes,
            center,
            radius,
        }
    }

    /// Per face: unit normal and offset `n . (a - center)` (f32, `a` the first corner), the
    /// offset NaN for a face whose sine at `a` is below [`SLIVER`].
    pub fn planes(&self) -> &[[f32; 4]] {
        &self.planes
    }
}
