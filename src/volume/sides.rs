//! The leading and trailing surfaces' vertex maps and face order, for `assemble.rs`: two
//! parallel passes over fixed chunks of faces (the same result for any thread count).
use rayon::prelude::*;

/// Faces per chunk of the parallel passes over the faces below (fixed: the same for any
/// thread count).
const FACE_CHUNK: usize = 8192;

/// Set `lead[v]` (`trail[v]`) to 0 for every corner of a front (back) face.
pub(super) fn mark_sides(faces: &[[u32; 3]], front: &[bool], lead: &mut [u32], trail: &mut [u32]) {
    use std::sync::atomic::{AtomicBool, Ordering::Relaxed};
    if faces.len() <= FACE_CHUNK {
        for (face, &f) in faces.iter().zip(front) {
            let map = if f { &mut *lead } else { &mut *trail };
            for &i in face {
                map[i as usize] = 0;
            }
        }
        return;
    }
    // Plain (relaxed) stores of `true` only: the result does not depend on their order.
    let (l, t): (Vec<AtomicBool>, Vec<AtomicBool>) = (0..lead.len())
        .map(|_| (AtomicBool::new(false), AtomicBool::new(false)))
        .unzip();
    faces
        .par_chunks(FACE_CHUNK)
        .zip(front.par_chunks(FACE_CHUNK))
        .for_each(|(fs, fr)| {
            for (face, &f) in fs.iter().zip(fr) {
                let map = if f { &l } else { &t };
                for &i in face {
                    map[i as usize].store(true, Relaxed);
                }
            }
        });
    for (m, flags) in [(lead, &l), (trail, &t)] {
        for (x, b) in m.iter_mut().zip(flags) {
            if b.load(Relaxed) {
                *x = 0;
            }
        }
    }
}

/// The front faces through `lead`, in order, then the back faces through `trail`, in order
/// and the number of front faces: chunks counted, then written at their prefix offsets.
pub(super) fn leading_then_trailing(
    faces: &[[u32; 3]],
    front: &[bool],
    lead: &[u32],
    trail: &[u32],
) -> (Vec<[u32; 3]>, usize) {
    let mut out = vec![[0u32; 3]; faces.len()];
    let counts: Vec<usize> = front
        .par_chunks(FACE_CHUNK)
        .map(|c| c.iter().filter(|&&f| f).count())
        .collect();
    let leading = counts.iter().sum();
    let (mut lo, mut hi) = out.split_at_mut(leading);
    let mut parts = Vec::with_capacity(counts.len());
    for (ci, &c) in counts.iter().enumerate() {
        let size = FACE_CHUNK.min(faces.len() - ci * FACE_CHUNK);
        let (a, rest_lo) = std::mem::take(&mut lo).split_at_mut(c);
        let (b, rest_hi) = std::mem::take(&mut hi).split_at_mut(size - c);
        parts.push((a, b));
        (lo, hi) = (rest_lo, rest_hi);
    }
    parts
        .into_par_iter()
        .zip(
            faces
                .par_chunks(FACE_CHUNK)
                .zip(front.par_chunks(FACE_CHUNK)),
        )
        .for_each(|((a, b), (fs, fr))| {
            let (mut i, mut j) = (0, 0);
            for (face, &f) in fs.iter().zip(fr) {
                if f {
                    a[i] = face.map(|v| lead[v as usize]);
                    i += 1;
                } else {
                    b[j] = face.map(|v| trail[v as usize]);
                    j += 1;
                }
            }
        });
    (out, leading)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunked_side_passes_equal_the_serial_loops() {
        // Three chunks of faces with pseudo-random corners and sides.
        let nv = 5000u32;
        let faces: Vec<[u32; 3]> = (0..(2 * FACE_CHUNK + 77) as u32)
            .map(|i| [i % nv, (i * 7 + 3) % nv, (i * 13 + 11) % nv])
            .collect();
        let front: Vec<bool> = (0..faces.len()).map(|i| (i * 2654435761) % 7 < 3).collect();
        let (mut lead, mut trail) = (vec![u32::MAX; nv as usize], vec![u32::MAX; nv as usize]);
        for (face, &f) in faces.iter().zip(&front) {
            for &i in face {
                if f {
                    lead[i as usize] = 0;
                } else {
                    trail[i as usize] = 0;
                }
            }
        }
        // Distinct ids for the face pass.
        let ids = |m: &[u32], k: u32| -> Vec<u32> {
            m.iter()
                .enumerate()
                .map(|(v, &x)| if x == 0 { 2 * v as u32 + k } else { x })
                .collect()
        };
        let (lead_ids, trail_ids) = (ids(&lead, 0), ids(&trail, 1));
        let want_faces: Vec<[u32; 3]> = [true, false]
            .iter()
            .flat_map(|&w| {
                let map = if w { &lead_ids } else { &trail_ids };
                faces
                    .iter()
                    .zip(&front)
                    .filter(move |(_, &f)| f == w)
                    .map(move |(face, _)| face.map(|i| map[i as usize]))
            })
            .collect();
        for threads in [1, 2] {
            let (l, t, out) = crate::on_threads(threads, || {
                let (mut l, mut t) = (vec![u32::MAX; nv as usize], vec![u32::MAX; nv as usize]);
                mark_sides(&faces, &front, &mut l, &mut t);
                let out = leading_then_trailing(&faces, &front, &lead_ids, &trail_ids);
                (l, t, out)
            });
            assert_eq!((&l, &t), (&lead, &trail));
            assert_eq!(out.0, want_faces);
            assert_eq!(out.1, front.iter().filter(|&&f| f).count());
        }
    }
}
