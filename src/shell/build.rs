//! Building the shell mesh (section 3.3): one quad strip per live polygon, attached to the
//! current mesh, alpha falling by `initial_alpha / subdivisions` per pair.
//!
//! Polygons are visited in increasing index in fixed chunks; each chunk counts its vertices,
//! a prefix sum places the chunks, and every chunk fills its own disjoint slices, so the output
//! does not depend on the thread count. Only live polygons emit anything.
use rayon::prelude::*;

use super::blur_shell::{check_rows, BlurShell, ShellColor, CHUNK};
use crate::budget::Need;
use crate::error::Result;
use crate::mesh::normalize;

/// The shell mesh: strips of quads (two triangles each), culling off when drawn.
///
/// Strip of polygon `f` with `r` ring elements: `r + 1` pairs of vertices, pair `j` at
/// `2 * j` (first vertex of the edge as the face runs it) and `2 * j + 1`; quad `j` joins
/// pairs `j` and `j + 1` as triangles `(2j, 2j+1, 2j+3)` and `(2j, 2j+3, 2j+2)`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ShellMesh {
    /// World positions.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles over `vertices`.
    pub faces: Vec<[u32; 3]>,
    /// Straight (non-premultiplied) RGBA.
    pub rgba: Vec<[f32; 4]>,
    /// Unit normals (zero where the mesh normal was zero).
    pub normals: Vec<[f32; 3]>,
    /// Per shell vertex: the mesh polygon whose strip it belongs to.
    pub face: Vec<u32>,
    /// Per shell vertex: its pair index `j` along the strip (0 = base on the current mesh).
    pub step: Vec<u8>,
}

/// Output slices of one build, sized by a [`BuildPlan`]. The index types are generic so the
/// Python binding can fill numpy's int64 / int32 arrays directly (`I`: triangle corners, `J`:
/// source polygon, `K`: step).
pub struct ShellOut<'a, I, J, K> {
    /// World positions of the shell's vertices.
    pub vertices: &'a mut [[f64; 3]],
    /// Triangles over `vertices`.
    pub faces: &'a mut [[I; 3]],
    /// Straight RGBA per vertex.
    pub rgba: &'a mut [[f32; 4]],
    /// Unit normals per vertex.
    pub normals: &'a mut [[f32; 3]],
    /// Per vertex, the mesh polygon whose strip it belongs to.
    pub face: &'a mut [J],
    /// Per vertex, its pair index along the strip.
    pub step: &'a mut [K],
}

/// The sizes of the next build (and where each chunk of polygons writes).
#[derive(Debug, Clone, Default)]
pub struct BuildPlan {
    /// Pairs and strips per chunk of `CHUNK` polygons.
    counts: Vec<(usize, usize)>,
    /// Shell vertices (two per pair).
    pub n_vertices: usize,
    /// Shell triangles (two per quad, quads = pairs - strips).
    pub n_triangles: usize,
}

impl BlurShell {
    /// Pairs emitted by polygon `f` (0 when its strip is dead).
    #[inline]
    fn pairs(&self, f: usize) -> usize {
        // The fade byte first: most polygons have a dead strip and their `hot` is not read.
        if (self.fade[f] as u32) >= self.opts.subdivisions {
            return 0;
        }
        match self.hot[f].run {
            0 => 0,
            run => run as usize + 1,
        }
    }

    /// The shell mesh after the last update. `vertices` / `normals` (V,3): the current mesh
    /// when it has moved since the last update (the paper's frames between updates); by default
    /// the positions and normals of the last update. Errors name `vertices` or `normals`.
    pub fn build(
        &self,
        vertices: Option<&[[f64; 3]]>,
        normals: Option<&[[f64; 3]]>,
    ) -> Result<ShellMesh> {
        let plan = self.build_plan(vertices, normals)?;
        let (nv, nt) = (plan.n_vertices, plan.n_triangles);
        let mut mesh = ShellMesh {
            vertices: vec![[0.0; 3]; nv],
            faces: vec![[0; 3]; nt],
            rgba: vec![[0.0; 4]; nv],
            normals: vec![[0.0; 3]; nv],
            face: vec![0; nv],
            step: vec![0; nv],
        };
        let out = ShellOut {
            vertices: &mut mesh.vertices,
            faces: &mut mesh.faces,
            rgba: &mut mesh.rgba,
            normals: &mut mesh.normals,
            face: &mut mesh.face,
            step: &mut mesh.step,
        };
        self.build_into(&plan, out, vertices, normals);
        Ok(mesh)
    }

    /// Check `vertices` / `normals` as [`BlurShell::build`] does and size the shell.
    pub fn build_plan(
        &self,
        vertices: Option<&[[f64; 3]]>,
        normals: Option<&[[f64; 3]]>,
    ) -> Result<BuildPlan> {
        if let Some(v) = vertices {
            check_rows(v, self.n_vertices, "vertices", self.parallel())?;
        }
        if let Some(n) = normals {
            check_rows(n, self.n_vertices, "normals", self.parallel())?;
        }
        if self.updates == 0 {
            return Ok(BuildPlan::default());
        }
        let nf = self.faces.len();
        let count = |c: usize| {
            (c * CHUNK..((c + 1) * CHUNK).min(nf)).fold((0, 0), |(p, s), f| {
                let k = self.pairs(f);
                (p + k, s + usize::from(k > 0))
            })
        };
        let counts: Vec<(usize, usize)> = if self.parallel() {
            (0..nf.div_ceil(CHUNK)).into_par_iter().map(count).collect()
        } else {
            (0..nf.div_ceil(CHUNK)).map(count).collect()
        };
        let n_pairs: usize = counts.iter().map(|c| c.0).sum();
        let n_triangles: usize = counts.iter().map(|&(p, s)| 2 * (p - s)).sum();
        // The shell mesh: 64 bytes a vertex (position, colour, normal, face, step), 24 a
        // triangle, checked against the memory budget before the caller allocates it.
        Need::new("BlurShell.build")
            .add(&[("strip vertices", 2 * n_pairs as u64)], 64)?
            .add(&[("strip triangles", n_triangles as u64)], 24)?
            .check()?;
        Ok(BuildPlan {
            counts,
            n_vertices: 2 * n_pairs,
            n_triangles,
        })
    }

    /// Fill `out` (sized by `plan`, from [`BlurShell::build_plan`] with the same arguments and
    /// no update in between) with the shell mesh; see [`BlurShell::build`].
    pub fn build_into<I, J, K>(
        &self,
        plan: &BuildPlan,
        out: ShellOut<'_, I, J, K>,
        vertices: Option<&[[f64; 3]]>,
        normals: Option<&[[f64; 3]]>,
    ) where
        I: From<u32> + Send,
        J: From<u32> + Send,
        K: From<u8> + Send,
    {
        assert!(out.vertices.len() == plan.n_vertices && out.faces.len() == plan.n_triangles);
        let mut jobs = Vec::with_capacity(plan.counts.len());
        let (mut v, mut t, mut c, mut n, mut fa, mut st) = (
            out.vertices,
            out.faces,
            out.rgba,
            out.normals,
            out.face,
            out.step,
        );
        let mut v0 = 0u32;
        for (ci, &(p, s)) in plan.counts.iter().enumerate() {
            let nvx = 2 * p;
            let ntri = 2 * (p - s);
            let (vh, vt) = v.split_at_mut(nvx);
            let (th, tt) = t.split_at_mut(ntri);
            let (ch, ct) = c.split_at_mut(nvx);
            let (nh, nt) = n.split_at_mut(nvx);
            let (fh, ft) = fa.split_at_mut(nvx);
            let (sh, stl) = st.split_at_mut(nvx);
            let out = ShellOut {
                vertices: vh,
                faces: th,
                rgba: ch,
                normals: nh,
                face: fh,
                step: sh,
            };
            jobs.push((ci, v0, out));
            v0 += nvx as u32;
            (v, t, c, n, fa, st) = (vt, tt, ct, nt, ft, stl);
        }
        let fill = |(ci, v0, out)| self.fill_chunk(ci, v0, out, vertices, normals);
        if self.parallel() {
            jobs.into_par_iter().for_each(fill);
        } else {
            jobs.into_iter().for_each(fill);
        }
    }

    fn fill_chunk<I: From<u32>, J: From<u32>, K: From<u8>>(
        &self,
        ci: usize,
        v0: u32,
        o: ShellOut<'_, I, J, K>,
        base_pos: Option<&[[f64; 3]]>,
        base_nrm: Option<&[[f64; 3]]>,
    ) {
        let s = self.opts.subdivisions as usize;
        let nf = self.faces.len();
        let a0 = self.opts.initial_alpha;
        let sf = s as f32;
        let m = self.updates - 1;
        let newest = (m % s as u64) as usize;
        let (mut vi, mut ti) = (0usize, 0usize);
        for f in ci * CHUNK..((ci + 1) * CHUNK).min(nf) {
            let pairs = self.pairs(f);
            if pairs == 0 {
                continue;
            }
            let (st, fade) = (self.hot[f], self.fade[f]);
            let face = self.faces[f];
            let iface = self.loc.ifaces[f];
            let start = vi;
            for j in 0..pairs {
                let (k, slot) = if j == 0 {
                    (st.last, newest)
                } else {
                    let slot = (newest + s - (j - 1) % s) % s;
                    (self.ring[slot * nf + f] & 3, slot)
                };
                let alpha = a0 * (1.0 - (j.max(fade as usize) as f32) / sf);
                let corners = [k as usize, (k as usize + 1) % 3];
                let buf = self.buf_of_slot[slot];
                // Both unit normals of the pair at once (two square roots per instruction).
                let units = unit2(
                    self.raw_normal(buf, iface[corners[0]] as usize),
                    self.raw_normal(buf, iface[corners[1]] as usize),
                );
                for (side, &corner) in corners.iter().enumerate() {
                    let (vtx, ivtx) = (face[corner] as usize, iface[corner] as usize);
                    let w = vi + side;
                    let p = self.pos_bufs[buf][ivtx];
                    o.vertices[w] = match (j, base_pos) {
                        (0, Some(b)) => b[vtx],
                        _ => [p[0] as f64, p[1] as f64, p[2] as f64],
                    };
                    o.normals[w] = match (j, base_nrm) {
                        (0, Some(n)) => {
                            let u = normalize(n[vtx]);
                            [u[0] as f32, u[1] as f32, u[2] as f32]
                        }
                        _ => units[side],
                    };
                    let c = match &self.color {
                        ShellColor::Uniform(c) => *c,
                        ShellColor::PerVertex(c) => c[vtx],
                    };
                    o.rgba[w] = [c[0], c[1], c[2], alpha * c[3]];
                    o.face[w] = J::from(f as u32);
                    o.step[w] = K::from(j as u8);
                }
                vi += 2;
            }
            for j in 0..pairs - 1 {
                let b = v0 + (start + 2 * j) as u32;
                o.faces[ti] = [b, b + 1, b + 3].map(I::from);
                o.faces[ti + 1] = [b, b + 3, b + 2].map(I::from);
                ti += 2;
            }
        }
        debug_assert_eq!(vi, o.vertices.len());
        debug_assert_eq!(ti, o.faces.len());
    }
}

/// Two float32 vectors made unit in float64 and rounded back, bit for bit as
/// `crate::mesh::normalize` (zero when the length is zero or not finite): on x86-64 in the
/// two lanes of SSE2 registers (IEEE square root and division, so the same values).
#[inline]
pub(crate) fn unit2(a: [f32; 3], b: [f32; 3]) -> [[f32; 3]; 2] {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        // SAFETY: SSE2 is part of the x86-64 baseline.
        unsafe {
            let x = _mm_set_pd(b[0] as f64, a[0] as f64);
            let y = _mm_set_pd(b[1] as f64, a[1] as f64);
            let z = _mm_set_pd(b[2] as f64, a[2] as f64);
            // (x x + y y) + z z, as `dot`.
            let l2 = _mm_add_pd(
                _mm_add_pd(_mm_mul_pd(x, x), _mm_mul_pd(y, y)),
                _mm_mul_pd(z, z),
            );
            let l = _mm_sqrt_pd(l2);
            let ok = _mm_and_pd(
                _mm_cmpgt_pd(l, _mm_setzero_pd()),
                _mm_cmplt_pd(l, _mm_set1_pd(f64::INFINITY)),
            );
            let q = |v| _mm_and_pd(_mm_div_pd(v, l), ok);
            let (qx, qy, qz) = (q(x), q(y), q(z));
            let mut out = [[0.0f64; 2]; 3];
            _mm_storeu_pd(out[0].as_mut_ptr(), qx);
            _mm_storeu_pd(out[1].as_mut_ptr(), qy);
            _mm_storeu_pd(out[2].as_mut_ptr(), qz);
            [
                [out[0][0] as f32, out[1][0] as f32, out[2][0] as f32],
                [out[0][1] as f32, out[1][1] as f32, out[2][1] as f32],
            ]
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let unit = |n: [f32; 3]| {
            let u = normalize([n[0] as f64, n[1] as f64, n[2] as f64]);
            [u[0] as f32, u[1] as f32, u[2] as f32]
        };
        [unit(a), unit(b)]
    }
}
