//! One mesh to draw: positions, faces, straight colours, normals, id, culling, previous positions.
use super::options::Shading;
use crate::error::{Error, Result};

/// Largest coordinate magnitude accepted: the one coordinate range of every entry point.
pub use crate::mesh::MAX_COORD;
/// Largest face count of one frame (triangle references are packed in 32 bits).
pub const MAX_FACES: usize = 1 << 28;

/// One mesh. Colours are straight (not premultiplied) linear RGBA, one for the whole mesh or one
/// per vertex. `previous` holds the world positions at the previous time (for velocity).
#[derive(Clone, Debug)]
pub struct Draw {
    /// World positions (V,3).
    pub vertices: Vec<[f64; 3]>,
    /// Counter-clockwise triangles over `vertices`.
    pub faces: Vec<[u32; 3]>,
    /// One colour for the mesh or one per vertex.
    pub rgba: Vec<[f32; 4]>,
    /// Per-vertex normals for lambert shading; `None`: area-weighted vertex normals.
    pub normals: Option<Vec<[f32; 3]>>,
    /// Written to the frame's ids where the mesh is nearest.
    pub object_id: i32,
    /// Whether back-facing triangles are culled.
    pub cull_back: bool,
    /// World positions at the previous time, for the velocity buffer.
    pub previous: Option<Vec<[f64; 3]>>,
    /// This mesh's shading when it differs from the frame's (`Options::shading`): one call
    /// then draws flat and lambert meshes, their transparent surfaces sorted together.
    pub shading: Option<Shading>,
}

/// Faces from signed indices, each checked to lie in `0..n_vertices`.
pub fn faces_from_i64(faces: &[i64], n_vertices: usize) -> Result<Vec<[u32; 3]>> {
    if faces.len() % 3 != 0 {
        return Err(Error::shape("faces", "expected shape (F,3)"));
    }
    let mut out = Vec::with_capacity(faces.len() / 3);
    for f in faces.chunks_exact(3) {
        let mut t = [0u32; 3];
        for k in 0..3 {
            let i = f[k];
            if i < 0 || i as u64 >= n_vertices as u64 {
                return Err(Error::value(
                    "faces",
                    format!("index {i} out of range for {n_vertices} vertices"),
                ));
            }
            t[k] = i as u32;
        }
        out.push(t);
    }
    Ok(out)
}

fn check_points(name: &'static str, p: &[[f64; 3]]) -> Result<()> {
    for v in p {
        for c in v {
            if !c.is_finite() {
                return Err(Error::value(name, "contains NaN or inf"));
            }
            if c.abs() > MAX_COORD {
                return Err(Error::value(
                    name,
                    format!("coordinates beyond the coordinate range +-{MAX_COORD:e} (MAX_COORD)"),
                ));
            }
        }
    }
    Ok(())
}

impl Draw {
    /// Checks shapes, ranges and values; every error names the argument.
    pub fn validate(&self) -> Result<()> {
        let n = self.vertices.len();
        if n == 0 {
            return Err(Error::shape("vertices", "is empty"));
        }
        if n > u32::MAX as usize {
            return Err(Error::shape("vertices", "too many vertices"));
        }
        check_points("vertices", &self.vertices)?;
        if self.faces.len() > MAX_FACES {
            return Err(Error::shape(
                "faces",
                format!("more than {MAX_FACES} faces"),
            ));
        }
        for f in &self.faces {
            if f.iter().any(|&i| i as usize >= n) {
                return Err(Error::value(
                    "faces",
                    format!("index out of range for {n} vertices"),
                ));
            }
        }
        if self.rgba.len() != 1 && self.rgba.len() != n {
            return Err(Error::shape(
                "rgba",
                "expected one colour or one per vertex",
            ));
        }
        for c in &self.rgba {
            if c.iter().any(|x| !x.is_finite()) {
                return Err(Error::value("rgba", "contains NaN or inf"));
            }
            if c[..3].iter().any(|&x| x < 0.0) {
                return Err(Error::value("rgba", "colours must be >= 0"));
            }
            if !(0.0..=1.0).contains(&c[3]) {
                return Err(Error::value("rgba", "alpha must be in [0, 1]"));
            }
        }
        if let Some(nrm) = &self.normals {
            if nrm.len() != n {
                return Err(Error::shape("normals", "expected one normal per vertex"));
            }
            if nrm.iter().flatten().any(|x| !x.is_finite()) {
                return Err(Error::value("normals", "contains NaN or inf"));
            }
        }
        if let Some(prev) = &self.previous {
            if prev.len() != n {
                return Err(Error::shape(
                    "previous_vertices",
                    "expected the shape of vertices",
                ));
            }
            check_points("previous_vertices", prev)?;
        }
        Ok(())
    }

    /// The colour of vertex `i` (straight alpha).
    #[inline]
    pub fn colour(&self, i: u32) -> [f32; 4] {
        if self.rgba.len() == 1 {
            self.rgba[0]
        } else {
            self.rgba[i as usize]
        }
    }

    /// Range of straight alpha over a face: (min, max).
    #[inline]
    pub fn alpha_range(&self, f: [u32; 3]) -> (f32, f32) {
        if self.rgba.len() == 1 {
            let a = self.rgba[0][3];
            return (a, a);
        }
        let a = f.map(|i| self.rgba[i as usize][3]);
        (a[0].min(a[1]).min(a[2]), a[0].max(a[1]).max(a[2]))
    }
}

/// Area-weighted vertex normals (the sum of the faces' cross products, normalised). Vertices no
/// face uses, or whose faces cancel, get a zero normal.
pub fn vertex_normals(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> Vec<[f32; 3]> {
    let mut acc = vec![[0.0f64; 3]; vertices.len()];
    for f in faces {
        let [a, b, c] = f.map(|i| vertices[i as usize]);
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        for &i in f {
            let s = &mut acc[i as usize];
            s[0] += n[0];
            s[1] += n[1];
            s[2] += n[2];
        }
    }
    acc.iter()
        .map(|n| {
            let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            if l > 0.0 && l.is_finite() {
                [(n[0] / l) as f32, (n[1] / l) as f32, (n[2] / l) as f32]
            } else {
                [0.0; 3]
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> Draw {
        Draw {
            vertices: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            faces: vec![[0, 1, 2]],
            rgba: vec![[1.0, 0.5, 0.25, 1.0]],
            normals: None,
            object_id: 3,
            cull_back: true,
            previous: None,
            shading: None,
        }
    }

    #[test]
    fn valid_draw_passes_and_bad_ones_name_the_argument() {
        assert!(tri().validate().is_ok());
        let mut d = tri();
        d.faces[0][2] = 3;
        assert!(d.validate().unwrap_err().to_string().starts_with("faces"));
        let mut d = tri();
        d.vertices[1][0] = f64::NAN;
        assert!(d
            .validate()
            .unwrap_err()
            .to_string()
            .starts_with("vertices"));
        let mut d = tri();
        d.rgba[0][3] = 1.5;
        assert!(d.validate().unwrap_err().to_string().starts_with("rgba"));
        let mut d = tri();
        d.previous = Some(vec![[0.0; 3]; 2]);
        assert!(d
            .validate()
            .unwrap_err()
            .to_string()
            .starts_with("previous_vertices"));
        assert!(faces_from_i64(&[0, 1, -1], 3).is_err());
        assert!(faces_from_i64(&[0, 1, 2], 3).is_ok());
    }

    #[test]
    fn normals_of_a_ccw_triangle_point_plus_z() {
        let d = tri();
        let n = vertex_normals(&d.vertices, &d.faces);
        for v in n {
            assert_eq!(v, [0.0, 0.0, 1.0]);
        }
    }
}
