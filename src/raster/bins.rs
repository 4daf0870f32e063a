//! The tile grid and binning: which triangles touch which screen tile, in submission order.
//!
//! A triangle reference packs its chunk index (high 16 bits) and its index in the chunk (low 16
//! bits). Chunks are numbered in submission order (draw by draw, face by face), so references
//! ascend in submission order, and a counting sort by tile keeps that order inside every bin.
//!
//! Both passes run in parallel over chunks: each chunk counts its triangles per tile, a prefix
//! sum in (tile, chunk) order gives every chunk its own run of slots in every bin, and each chunk
//! writes its references into its runs. The buffers are kept by the caller between frames
//! (`Bins::build` reuses them), so binning does not allocate once they have grown.
use super::setup::{Chunk, Tri};
use crate::budget::{try_reserve, Need};
use crate::error::Result;
use rayon::prelude::*;

/// Tile side in samples.
pub const TILE: i32 = 64;

/// The triangles of every tile: `refs[start[t]..start[t + 1]]` for tile `t` (row-major), and
/// copies of the triangles in the same order (`tris`), so that a tile reads its triangles in
/// sequence rather than gathering them from every chunk.
#[derive(Debug, Default)]
pub struct Bins {
    pub tiles_x: usize,
    pub tiles_y: usize,
    pub start: Vec<usize>,
    pub refs: Vec<u32>,
    pub tris: Vec<Tri>,
    /// Per chunk and tile (chunk-major): the triangle count, then the chunk's first slot.
    slots: Vec<usize>,
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

/// Calls `f(tile)` for every tile the triangle's box reaches.
#[inline(always)]
fn each_tile(bbox: [i32; 4], tiles_x: usize, mut f: impl FnMut(usize)) {
    let [x0, y0, x1, y1] = tile_range(bbox);
    for ty in y0..=y1 {
        for tx in x0..=x1 {
            f(ty * tiles_x + tx);
        }
    }
}

/// The reference and triangle arrays written by several chunks at once, each through its own
/// slots.
struct SharedRefs(*mut u32, *mut Tri);

// SAFETY: chunks write disjoint slots (see `Bins::build`), and nothing reads them meanwhile.
unsafe impl Send for SharedRefs {}
unsafe impl Sync for SharedRefs {}

impl Bins {
    /// Bins the set-up triangles for an internal image of `ws` x `hs` samples, reusing the
    /// buffers of the previous build. `need` is the rest of the frame's memory (the frame, the
    /// set-up): the counts per chunk and tile, and then the tiles' copies of the triangles once
    /// counted, are added to it and checked against the budget before they are allocated.
    pub fn build(&mut self, chunks: &[Chunk], ws: u32, hs: u32, need: Need) -> Result<()> {
        let tiles_x = (ws as usize).div_ceil(TILE as usize);
        let tiles_y = (hs as usize).div_ceil(TILE as usize);
        let n = tiles_x * tiles_y;
        self.tiles_x = tiles_x;
        self.tiles_y = tiles_y;
        let need = need.add(
            &[("face chunks", chunks.len() as u64), ("tiles", n as u64)],
            8,
        )?;
        need.check()?;
        // Counts per chunk and tile, in parallel.
        self.slots.clear();
        try_reserve(&mut self.slots, chunks.len() * n, "draws")?;
        self.slots.resize(chunks.len() * n, 0);
        if n > 0 {
            self.slots
                .par_chunks_mut(n)
                .zip(chunks.par_iter())
                .for_each(|(k, c)| {
                    for t in &c.tris {
                        each_tile(t.bbox, tiles_x, |i| k[i] += 1);
                    }
                });
        }
        // Prefix sum in (tile, chunk) order: bins in tile order, chunks in submission order
        // inside a bin. Each count becomes its chunk's first slot in that bin.
        self.start.clear();
        self.start.resize(n + 1, 0);
        let mut next = 0usize;
        for t in 0..n {
            self.start[t] = next;
            for c in 0..chunks.len() {
                let k = &mut self.slots[c * n + t];
                let count = *k;
                *k = next;
                next += count;
            }
        }
        self.start[n] = next;
        // Each triangle is copied into every tile its box reaches: a product of the draws'
        // triangles and the image's tiles, known only now.
        let each = (std::mem::size_of::<u32>() + std::mem::size_of::<Tri>()) as u64;
        need.add(&[("triangles x tiles they reach", next as u64)], each)?
            .check()?;
        self.refs.clear();
        try_reserve(&mut self.refs, next, "draws")?;
        self.refs.resize(next, 0);
        self.tris.clear();
        try_reserve(&mut self.tris, next, "draws")?;
        let out = SharedRefs(self.refs.as_mut_ptr(), self.tris.as_mut_ptr());
        let out = &out;
        if n > 0 {
            self.slots
                .par_chunks_mut(n)
                .zip(chunks.par_iter())
                .enumerate()
                .for_each(|(ci, (slot, c))| {
                    for (i, t) in c.tris.iter().enumerate() {
                        let r = ((ci as u32) << 16) | i as u32;
                        each_tile(t.bbox, tiles_x, |tile| {
                            // SAFETY: chunk ci owns slots slot[tile] .. slot[tile] + its count
                            // in this bin (the prefix sum above), all below `next` (the length
                            // of `refs`, the capacity of `tris`); each of its triangles in this
                            // bin takes one and advances.
                            unsafe {
                                *out.0.add(slot[tile]) = r;
                                out.1.add(slot[tile]).write(*t);
                            }
                            slot[tile] += 1;
                        });
                    }
                });
        }
        // SAFETY: the slots of all chunks in all bins are 0..next, each written once above
        // (the counts of the first pass are the triangles the second pass walks).
        unsafe { self.tris.set_len(next) };
        Ok(())
    }

    /// The references of tile `t` and their triangles.
    #[inline]
    pub fn tile(&self, t: usize) -> (&[u32], &[Tri]) {
        let range = self.start[t]..self.start[t + 1];
        (&self.refs[range.clone()], &self.tris[range])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::setup::Tri;

    fn tri(bbox: [i32; 4]) -> Tri {
        Tri {
            x: [0; 3],
            y: [0; 3],
            rx: [0.0; 3],
            ry: [0.0; 3],
            iw: [1.0; 3],
            bbox,
            verts: [0; 3],
            clip: 0,
            draw: 0,
            flags: 0,
        }
    }

    #[test]
    fn bins_hold_every_reaching_triangle_in_submission_order_and_are_reused() {
        let (ws, hs) = (300u32, 200u32);
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = |m: i32| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % m as u64) as i32
        };
        let mut bins = Bins::default();
        for round in 0..3 {
            let chunks: Vec<Chunk> = (0..5 + round)
                .map(|_| Chunk {
                    tris: (0..next(400))
                        .map(|_| {
                            let (x, y) = (next(ws as i32), next(hs as i32));
                            let (w, h) = (next(150), next(90));
                            tri([x, y, (x + w).min(ws as i32 - 1), (y + h).min(hs as i32 - 1)])
                        })
                        .collect(),
                    ..Default::default()
                })
                .collect();
            bins.build(&chunks, ws, hs, Need::new("test")).unwrap();
            for t in 0..bins.tiles_x * bins.tiles_y {
                let (tx, ty) = ((t % bins.tiles_x) as i32, (t / bins.tiles_x) as i32);
                let mut want = Vec::new();
                for (ci, c) in chunks.iter().enumerate() {
                    for (i, tr) in c.tris.iter().enumerate() {
                        let [x0, y0, x1, y1] = tr.bbox;
                        if x0 / TILE <= tx && tx <= x1 / TILE && y0 / TILE <= ty && ty <= y1 / TILE
                        {
                            want.push(((ci as u32) << 16) | i as u32);
                        }
                    }
                }
                let (refs, tris) = bins.tile(t);
                assert_eq!(refs, &want[..], "round {round} tile {t}");
                for (&r, t) in refs.iter().zip(tris) {
                    let c = &chunks[(r >> 16) as usize].tris[(r & 0xffff) as usize];
                    assert_eq!(t.bbox, c.bbox);
                }
            }
        }
    }
}
