//! Building the edge adjacency of a mesh (see [`crate::mesh::Adjacency`]): a two-level
//! counting sort of the half-edges on their lower vertex, parallel and independent of the thread
//! count.
use rayon::prelude::*;

use crate::mesh::Adjacency;

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
    let n_coarse = nv.div_ceil(width);
    let chunks = rayon::current_num_threads().clamp(1, 8);
    let per = faces.len().div_ceil(chunks).max(1);
    // (lower, higher, half-edge id * 2 + 1 if it runs lower -> higher); None for a zero-length
    // edge. Ids are below 3 * MAX_ELEMENTS < 2^31, so the code fits and sorts as the id does.
    let key = |f: &[u32; 3], h: u32, k: usize| {
        let (a, b) = (f[k], f[(k + 1) % 3]);
        (a != b).then(|| [a.min(b), a.max(b), ((h + k as u32) << 1) | u32::from(a < b)])
    };
    // 1. Coarse counts per chunk of faces, prefix sums, scatter.
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
    drop(cursors);
    drop(counts);
    // 2. Inside every coarse bucket: counting sort by vertex, sort each vertex's half-edges,
    //    count the edges (runs of equal higher vertex).
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
    drop(tmp);
    // 3. Fill edges and offsets per coarse bucket.
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
        let (entries, start) = (&entries, &start);
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
    let half_edges: Vec<u32> = entries.par_iter().map(|e| e.1 >> 1).collect();
    let forward: Vec<bool> = entries.par_iter().map(|e| e.1 & 1 == 1).collect();
    Adjacency {
        edges,
        offsets,
        half_edges,
        forward,
    }
}
