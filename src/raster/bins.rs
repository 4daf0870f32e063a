//! The tile grid and binning: which triangles touch which screen tile, in submission order.
//!
//! A triangle reference packs its chunk index (high 16 bits) and its index in the chunk (low 16
//! bits). Chunks are numbered in submission order (draw by draw, face by face), so references
//! ascend in submission order, and a counting sort by tile keeps that order inside every bin.
use super::setup::Chunk;
use rayon::prelude::*;

/// Tile side in samples.
pub const TILE: i32 = 64;

/// The triangles of every tile: `refs[start[t]..start[t + 1]]` for tile `t` (row-major).
#[derive(Debug, Default)]
pub struct Bins {
    pub tiles_x: usize,
    pub tiles_y: usize,
    pub start: Vec<usize>,
    pub refs: Vec<u32>,
}

#[inline]
fn tile_range(bbox: [i32; 4]) -> [usize; 4] {
    [
        (bbox[0] / TILE) as usize,
        (bbox[1] / TILE) as usize,
        (bbox[2] / TILE) as usize,
        (bbox[3] / TILE) as usize,
    ]
}

impl Bins {
    /// Bins the set-up triangles for an internal image of `ws` x `hs` samples.
    pub fn build(chunks: &[Chunk], ws: u32, hs: u32) -> Self {
        let tiles_x = (ws as usize).div_ceil(TILE as usize);
        let tiles_y = (hs as usize).div_ceil(TILE as usize);
        let n = tiles_x * tiles_y;
        // Per-chunk counts in parallel, then a prefix sum in chunk order.
        let counts: Vec<Vec<u32>> = chunks
            .par_iter()
            .map(|c| {
                let mut k = vec![0u32; n];
                for t in &c.tris {
                    let [x0, y0, x1, y1] = tile_range(t.bbox);
                    for ty in y0..=y1 {
                        for tx in x0..=x1 {
                            k[ty * tiles_x + tx] += 1;
                        }
                    }
                }
                k
            })
            .collect();
        let mut start = vec![0usize; n + 1];
        for k in &counts {
            for (t, &c) in k.iter().enumerate() {
                start[t + 1] += c as usize;
            }
        }
        for t in 0..n {
            start[t + 1] += start[t];
        }
        let mut refs = vec![0u32; start[n]];
        let mut next: Vec<usize> = start[..n].to_vec();
        for (ci, c) in chunks.iter().enumerate() {
            for (i, t) in c.tris.iter().enumerate() {
                let r = ((ci as u32) << 16) | i as u32;
                let [x0, y0, x1, y1] = tile_range(t.bbox);
                for ty in y0..=y1 {
                    for tx in x0..=x1 {
                        let slot = &mut next[ty * tiles_x + tx];
                        refs[*slot] = r;
                        *slot += 1;
                    }
                }
            }
        }
        Bins {
            tiles_x,
            tiles_y,
            start,
            refs,
        }
    }

    /// The references of tile `t`.
    #[inline]
    pub fn tile(&self, t: usize) -> &[u32] {
        &self.refs[self.start[t]..self.start[t + 1]]
    }
}
