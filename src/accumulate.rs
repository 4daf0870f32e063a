//! Accumulation-buffer kernels: the per-sample weighted, depth-tested sum of a moving layer and
//! the one composite over the static layer after the last sample.
//!
//! Layers are row-major `rgba` (N*4 floats, premultiplied) and `depth` (N floats, `inf` where
//! empty). Every output element depends on the same input elements only, so the result does not
//! depend on the thread count.
use rayon::prelude::*;

use crate::{Error, Result};

/// Elements per parallel job (a few rows of a typical window).
const CHUNK: usize = 8192;

/// `acc += weight * rgba` where `depth < limit` (everywhere when `limit` is None): the moving
/// layer's samples in front of the static surface.
pub fn accumulate(
    acc: &mut [f32],
    rgba: &[f32],
    depth: &[f32],
    limit: Option<&[f32]>,
    weight: f32,
) -> Result<()> {
    let n = depth.len();
    if acc.len() != 4 * n || rgba.len() != 4 * n {
        return Err(Error::shape(
            "rgba",
            "acc, rgba and depth must describe the same samples",
        ));
    }
    if let Some(l) = limit {
        if l.len() != n {
            return Err(Error::shape("limit", "must have one depth per sample"));
        }
    }
    if !weight.is_finite() {
        return Err(Error::value("weight", "must be finite"));
    }
    acc.par_chunks_mut(4 * CHUNK)
        .zip(rgba.par_chunks(4 * CHUNK))
        .enumerate()
        .for_each(|(c, (a, r))| {
            let base = c * CHUNK;
            for (i, (a4, r4)) in a.chunks_exact_mut(4).zip(r.chunks_exact(4)).enumerate() {
                let k = base + i;
                let front = match limit {
                    Some(l) => depth[k] < l[k],
                    None => true,
                };
                if front {
                    for j in 0..4 {
                        a4[j] += weight * r4[j];
                    }
                }
            }
        });
    Ok(())
}

/// `acc += under * (1 - acc.alpha)`: the accumulated layer over the static one.
pub fn over(acc: &mut [f32], under: &[f32]) -> Result<()> {
    if acc.len() != under.len() || acc.len() % 4 != 0 {
        return Err(Error::shape("under", "must have the shape of acc, (N*4,)"));
    }
    acc.par_chunks_mut(4 * CHUNK)
        .zip(under.par_chunks(4 * CHUNK))
        .for_each(|(a, u)| {
            for (a4, u4) in a.chunks_exact_mut(4).zip(u.chunks_exact(4)) {
                let k = 1.0 - a4[3];
                for j in 0..4 {
                    a4[j] += k * u4[j];
                }
            }
        });
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn masked_weighted_sum_then_over() {
        let mut acc = vec![0.0f32; 8];
        let rgba = [1.0, 0.5, 0.25, 1.0, 1.0, 1.0, 1.0, 1.0];
        let depth = [1.0, 3.0];
        let limit = [2.0, 2.0];
        accumulate(&mut acc, &rgba, &depth, Some(&limit), 0.5).unwrap();
        assert_eq!(acc, vec![0.5, 0.25, 0.125, 0.5, 0.0, 0.0, 0.0, 0.0]);
        over(&mut acc, &[0.0, 0.0, 1.0, 1.0, 0.0, 1.0, 0.0, 1.0]).unwrap();
        assert_eq!(acc, vec![0.5, 0.25, 0.625, 1.0, 0.0, 1.0, 0.0, 1.0]);
    }

    #[test]
    fn no_limit_adds_everywhere_and_shapes_are_checked() {
        let mut acc = vec![1.0f32; 4];
        accumulate(&mut acc, &[1.0; 4], &[f32::INFINITY], None, 2.0).unwrap();
        assert_eq!(acc, vec![3.0; 4]);
        assert!(accumulate(&mut acc, &[1.0; 8], &[1.0], None, 1.0).is_err());
        assert!(accumulate(&mut acc, &[1.0; 4], &[1.0], Some(&[]), 1.0).is_err());
        assert!(accumulate(&mut acc, &[1.0; 4], &[1.0], None, f32::NAN).is_err());
        assert!(over(&mut acc, &[0.0; 8]).is_err());
    }

    #[test]
    fn independent_of_the_thread_count() {
        let n = 3 * CHUNK + 17;
        let rgba: Vec<f32> = (0..4 * n).map(|i| (i % 13) as f32 * 0.1).collect();
        let depth: Vec<f32> = (0..n).map(|i| (i % 7) as f32).collect();
        let limit: Vec<f32> = (0..n).map(|i| (i % 5) as f32).collect();
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut acc = vec![0.0f32; 4 * n];
                accumulate(&mut acc, &rgba, &depth, Some(&limit), 0.3).unwrap();
                over(&mut acc, &rgba).unwrap();
                acc
            })
        };
        assert_eq!(run(1), run(2));
    }
}
