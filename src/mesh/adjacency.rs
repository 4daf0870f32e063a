//! The edge adjacency of a mesh, the face neighbours derived from it, and the faces around
//! each vertex. The adjacency is built
//! by a two-level counting sort of the half-edges on their lower vertex, parallel and
//! independent of the thread count.
use rayon::prelude::*;

/// The edge adjacency of a mesh.
///
/// `edges[e] = [a, b]` with `a < b`, sorted lexicographically. The half-edges of edge `e` are
/// `half_edges[offsets[e]..offsets[e + 1]]`, each `3 * face + k` for the face's edge
/// `faces[face][k] -> faces[face][(k + 1) % 3]`, in increasing order.
#[derive(Debug, Clone, PartialEq)]
pub struct Adjacency {
    /// Undirected edges `[a, b]`, `a < b`, sorted.
    pub edges: Vec<[u32; 2]>,
    /// Per edge, the start of its half-edges (one more entry than edges).
    pub offsets: Vec<u32>,
    /// Half-edges `3 * face + k`, grouped by edge.
    pub half_edges: Vec<u32>,
    /// Per half-edge (parallel to `half_edges`): runs from the lower to the higher index.
    pub forward: Vec<bool>,
}

impl Adjacency {
    /// Number of undirected edges.
    pub fn len(&self) -> usize {
        self.edges.len()
    }
    /// Whether the mesh has no edge.
    pub fn is_empty(&self) -> bool {
        self.edges.is_empty()
    }
    /// The half-edges (`3 * face + k`) of edge `e`.
    pub fn incident(&self, e: usize) -> &[u32] {
        &self.half_edges[self.offsets[e] as usize..self.offsets[e + 1] as usize]
    }
    /// The direction flags of the half-edges of edge `e` (see `forward`).
    pub fn incident_forward(&self, e: usize) -> &[bool] {
        &self.forward[self.offsets[e] as usize..self.offsets[e + 1] as usize]
    }

    /// The face across each edge of every face and the edge's index, or `None` unless every
    /// face edge has exactly one partner running it the other way (a closed, consistently wound,
    /// 2-manifold mesh without zero-length edges). `n_faces`: the mesh's face count.
    pub fn face_neighbors(&self, n_faces: usize) -> Option<FaceNeighbors> {
        use std::sync::atomic::{AtomicU32, Ordering::Relaxed};
        let n = 3 * n_faces;
        let across: Vec<AtomicU32> = (0..n).map(|_| AtomicU32::new(u32::MAX)).collect();
        let edge: Vec<AtomicU32> = (0..n).map(|_| AtomicU32::new(u32::MAX)).collect();
        // Every half-edge belongs to one edge, so each slot is written at most once.
        let paired = (0..self.len()).into_par_iter().with_min_len(4096).all(|e| {
            let (inc, fw) = (self.incident(e), self.incident_forward(e));
            if inc.len() != 2 || fw[0] == fw[1] {
                return false;
            }
            for (h, other) in [(inc[0], inc[1]), (inc[1], inc[0])] {
                across[h as usize].store(other / 3, Relaxed);
                edge[h as usize].store(e as u32, Relaxed);
            }
            true
        });
        let triples = |a: &[AtomicU32]| -> Vec<[u32; 3]> {
            a.par_chunks(3)
                .map(|c| [c[0].load(Relaxed), c[1].load(Relaxed), c[2].load(Relaxed)])
                .collect()
        };
        let faces = triples(&across);
        (paired && faces.par_iter().all(|n| !n.contains(&u32::MAX))).then(|| FaceNeighbors {
            faces,
            edges: triples(&edge),
        })
    }
}

/// Per face `f` and edge `k` (`faces[f][k] -> faces[f][(k + 1) % 3]`): the face across it and
/// the edge's index in the adjacency.
#[derive(Debug, Clone, PartialEq)]
pub struct FaceNeighbors {
    /// The face across each edge.
    pub faces: Vec<[u32; 3]>,
    /// The index of each edge in the adjacency.
    pub edges: Vec<[u32; 3]>,
}

/// The faces around each vertex (a CSR table), in increasing face order; a face that repeats a
/// vertex is listed once per corner, as `np.add.at` would add it.
#[derive(Debug, Clone)]
pub struct VertexFaces {
    offsets: Vec<u32>,
    faces: Vec<u32>,
}

impl VertexFaces {
    /// The table of `faces` over `n_vertices` vertices.
    pub fn new(faces: &[[u32; 3]], n_vertices: usize) -> Self {
        let mut offsets = vec![0u32; n_vertices + 1];
        for f in faces {
            for &i in f {
                offsets[i as usize + 1] += 1;
            }
        }
        for i in 0..n_vertices {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut out = vec![0u32; 3 * faces.len()];
        for (fi, f) in faces.iter().enumerate() {
            for &i in f {
                out[fill[i as usize] as usize] = fi as u32;
                fill[i as usize] += 1;
            }
        }
        VertexFaces {
            offsets,
            faces: out,
        }
    }

    /// The faces of vertex `v`, in order.
    #[inline]
    pub fn faces_of(&self, v: usize) -> &[u32] {
        &self.faces[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }

    /// Renames every listed face `f` to `rename(f)`, keeping the order of each vertex's list.
    pub fn rename_faces(&mut self, rename: impl Fn(u32) -> u32) {
        for f in &mut self.faces {
            *f = rename(*f);
        }
    }

    /// Unnormalised vertex normal of `v`: the sum of `face_n` over its faces, in order, from 0.
    #[inline]
    pub fn normal(&self, v: usize, face_n: &[[f32; 3]]) -> [f32; 3] {
        let mut acc = [0.0f32; 3];
        for &f in &self.faces[self.offsets[v] as usize..self.offsets[v + 1] as usize] {
            let n = face_n[f as usize];
            acc[0] += n[0];
            acc[1] += n[1];
            acc[2] += n[2];
        }
        acc
    }
}

/// A raw pointer shared by the scatter threads; each writes its own disjoint slots.
struct SharedSlots<T>(*mut T);
unsafe impl<T: Send> Sync for SharedSlots<T> {}
unsafe impl<T: Send> Send for SharedSlots<T> {}

/// Build the adjacency by a two-level counting sort of the half-edges on their lower vertex:
/// first into coarse buckets of `width` consecutive vertices (per-chunk counts and disjoint
/// scatter, few streams so the writes stay in cache), then inside each coarse bucket, in
/// parallel and cache-resident, by vertex, with each vertex's few half-edges sorted by (higher
/// vertex, half-edge id); runs of equal keys are the edges. Every bucket ends up sorted whatever
/// the chunking, so the result does not depend on the thread count.
pub fn build_adjacency(faces: &[[u32; 3]], n_vertices: usize) -> Adjacency {
    let nv = n_vertices.max(1);
    let width = nv.div_ceil(1024).max(1);
    let (tmp, coarse_start) = coarse_scatter(faces, nv, width);
    let (entries, start, run_counts) = sort_buckets(tmp, &coarse_start, nv, width);
    let (edges, offsets) = edges_of(&entries, &start, &run_counts, width, n_vertices);
    let half_edges: Vec<u32> = entries.par_iter().map(|e| e.1 >> 1).collect();
    let forward: Vec<bool> = entries.par_iter().map(|e| e.1 & 1 == 1).collect();
    Adjacency {
        edges,
        offsets,
        half_edges,
        forward,
    }
}

/// Step 1 of [`build_adjacency`]: every half-edge's key `(lower, higher, id * 2 + forward)`
/// scattered into coarse buckets of `width` consecutive lower vertices (counts per chunk of
/// faces, prefix sums, a disjoint parallel scatter); returns the keys and each bucket's start
/// (`nv.div_ceil(width) + 1` of them).
fn coarse_scatter(faces: &[[u32; 3]], nv: usize, width: usize) -> (Vec<[u32; 3]>, Vec<usize>) {
    let n_coarse = nv.div_ceil(width);
    let chunks = rayon::current_num_threads().clamp(1, 8);
    let per = faces.len().div_ceil(chunks).max(1);
    // (lower, higher, half-edge id * 2 + 1 if it runs lower -> higher); None for a zero-length
    // edge. Ids are below 3 * MAX_ELEMENTS < 2^31, so the code fits and sorts as the id does.
    let key = |f: &[u32; 3], h: u32, k: usize| {
        let (a, b) = (f[k], f[(k + 1) % 3]);
        (a != b).then(|| [a.min(b), a.max(b), ((h + k as u32) << 1) | u32::from(a < b)])
    };
    let counts: Vec<Vec<u32>> = faces
        .par_chunks(per)
        .map(|part| {
            let mut c = vec![0u32; n_coarse];
            for f in part {
                for k in 0..3 {
                    if f[k] != f[(k + 1) % 3] {
                        c[f[k].min(f[(k + 1) % 3]) as usize / width] += 1;
                    }
                }
            }
            c
        })
        .collect();
    let mut coarse_start = vec![0usize; n_coarse + 1];
    let mut cursors: Vec<Vec<usize>> = vec![vec![0usize; n_coarse]; counts.len()];
    let mut acc = 0usize;
    for b in 0..n_coarse {
        coarse_start[b] = acc;
        for (c, cur) in counts.iter().zip(cursors.iter_mut()) {
            cur[b] = acc;
            acc += c[b] as usize;
        }
    }
    coarse_start[n_coarse] = acc;
    let total = acc;
    let mut tmp = vec![[0u32; 3]; total];
    let slots = SharedSlots(tmp.as_mut_ptr());
    faces
        .par_chunks(per)
        .zip(cursors.par_iter_mut())
        .enumerate()
        .for_each(|(ci, (part, cur))| {
            let slots = &slots;
            for (i, f) in part.iter().enumerate() {
                let h = 3 * (ci * per + i) as u32;
                for k in 0..3 {
                    if let Some(e) = key(f, h, k) {
                        let slot = &mut cur[e[0] as usize / width];
                        // SAFETY: chunk `ci` owns slots [cursor_ci[b], cursor_ci[b] + count_ci[b]) of
                        // every coarse bucket b; these ranges are disjoint and inside `tmp`.
                        unsafe { *slots.0.add(*slot) = e };
                        *slot += 1;
                    }
                }
            }
        });
    (tmp, coarse_start)
}

/// Step 2 of [`build_adjacency`]: inside every coarse bucket of `tmp` (from `coarse_scatter`),
/// a counting sort by vertex, each vertex's half-edges sorted by (higher vertex, key); returns
/// the `(higher, key)` entries, each vertex's first entry (`nv + 1`) and the number of edges
/// (runs of equal higher vertex) per bucket.
fn sort_buckets(
    tmp: Vec<[u32; 3]>,
    coarse_start: &[usize],
    nv: usize,
    width: usize,
) -> (Vec<(u32, u32)>, Vec<u32>, Vec<usize>) {
    let n_coarse = coarse_start.len() - 1;
    let total = coarse_start[n_coarse];
    let mut entries = vec![(0u32, 0u32); total];
    let mut start = vec![0u32; nv + 1];
    let mut run_counts = vec![0usize; n_coarse];
    {
        let mut jobs = Vec::with_capacity(n_coarse);
        type Rests<'a> = (&'a [[u32; 3]], &'a mut [(u32, u32)], &'a mut [u32]);
        let (mut t_rest, mut e_rest, mut s_rest): Rests<'_> =
            (&tmp, &mut entries, &mut start[..nv]);
        for (b, rc) in run_counts.iter_mut().enumerate() {
            let len = coarse_start[b + 1] - coarse_start[b];
            let (th, tt) = t_rest.split_at(len);
            let (eh, et) = e_rest.split_at_mut(len);
            let (sh, st) = s_rest.split_at_mut(width.min(s_rest.len()));
            jobs.push((b, th, eh, sh, rc));
            (t_rest, e_rest, s_rest) = (tt, et, st);
        }
        jobs.into_par_iter().for_each(|(b, src, dst, st, rc)| {
            let v0 = b * width;
            let base = coarse_start[b];
            let mut local = vec![0u32; st.len() + 1];
            for e in src {
                local[e[0] as usize - v0 + 1] += 1;
            }
            for i in 0..st.len() {
                local[i + 1] += local[i];
            }
            for (s, l) in st.iter_mut().zip(&local) {
                *s = (base + *l as usize) as u32;
            }
            let mut fill = local.clone();
            for e in src {
                let slot = &mut fill[e[0] as usize - v0];
                dst[*slot as usize] = (e[1], e[2]);
                *slot += 1;
            }
            let mut runs = 0;
            for w in local.windows(2) {
                let bucket = &mut dst[w[0] as usize..w[1] as usize];
                bucket.sort_unstable();
                runs += bucket
                    .iter()
                    .enumerate()
                    .filter(|(i, e)| *i == 0 || bucket[i - 1].0 != e.0)
                    .count();
            }
            *rc = runs;
        });
    }
    start[nv] = total as u32;
    (entries, start, run_counts)
}

/// Step 3 of [`build_adjacency`]: the edges `[lower, higher]` and each edge's first entry
/// (its half-edges' offsets), filled per coarse bucket in parallel.
fn edges_of(
    entries: &[(u32, u32)],
    start: &[u32],
    run_counts: &[usize],
    width: usize,
    n_vertices: usize,
) -> (Vec<[u32; 2]>, Vec<u32>) {
    let n_coarse = run_counts.len();
    let total = entries.len();
    let n_edges: usize = run_counts.iter().sum();
    let mut edges = vec![[0u32; 2]; n_edges];
    let mut offsets = vec![0u32; n_edges + 1];
    offsets[n_edges] = total as u32;
    {
        let mut jobs = Vec::with_capacity(n_coarse);
        let (mut e_rest, mut o_rest): (&mut [[u32; 2]], &mut [u32]) =
            (&mut edges, &mut offsets[..n_edges]);
        for (b, &n) in run_counts.iter().enumerate() {
            let (eh, et) = e_rest.split_at_mut(n);
            let (oh, ot) = o_rest.split_at_mut(n);
            jobs.push((b, eh, oh));
            (e_rest, o_rest) = (et, ot);
        }
        jobs.into_par_iter().for_each(|(b, e_out, o_out)| {
            let mut j = 0;
            for a in b * width..((b + 1) * width).min(n_vertices) {
                let s = start[a] as usize;
                let bucket = &entries[s..start[a + 1] as usize];
                for (i, e) in bucket.iter().enumerate() {
                    if i == 0 || bucket[i - 1].0 != e.0 {
                        e_out[j] = [a as u32, e.0];
                        o_out[j] = (s + i) as u32;
                        j += 1;
                    }
                }
            }
        });
    }
    (edges, offsets)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn adjacency_is_thread_count_independent() {
        let faces: Vec<[u32; 3]> = (0..50000u32)
            .map(|i| [i % 4999, (i * 7 + 1) % 4999, (i * 13 + 5) % 4999])
            .collect();
        let a = crate::on_threads(1, || build_adjacency(&faces, 4999));
        let b = crate::on_threads(3, || build_adjacency(&faces, 4999));
        assert_eq!(a, b);
        // Against a plain sort of all half-edges.
        let mut all: Vec<(u32, u32, u32)> = Vec::new();
        for (i, f) in faces.iter().enumerate() {
            for k in 0..3 {
                let (x, y) = (f[k], f[(k + 1) % 3]);
                if x != y {
                    all.push((x.min(y), x.max(y), 3 * i as u32 + k as u32));
                }
            }
        }
        all.sort_unstable();
        assert_eq!(a.half_edges, all.iter().map(|t| t.2).collect::<Vec<_>>());
        let mut keys: Vec<[u32; 2]> = all.iter().map(|t| [t.0, t.1]).collect();
        keys.dedup();
        assert_eq!(a.edges, keys);
    }
}
