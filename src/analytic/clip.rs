//! The clip positions one strip of a frame uses, held compactly: a frame set up strip by strip
//! (`strips.rs`) would otherwise hold every vertex's clip position at every segment boundary
//! (32 bytes each: a turning mesh of 48k vertices over 128 segments, 200 MB), of which a strip's
//! triangles use a tenth or less.
//!
//! The points used are marked in a bit set (one bit per boundary and vertex), and only they
//! are computed and kept, in index order; a point is found by the rank of its bit (the marked
//! bits before it). Each point is computed by the same arithmetic as a whole frame's, so its
//! bits are the same.
use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;

/// Words of marks whose points are computed by one parallel job.
const RUN: usize = 1024;

/// Marks of the points `0..n` one strip uses, set from any thread.
pub struct Marks(Vec<AtomicU64>);

impl Marks {
    /// No point marked of `n`.
    pub fn new(n: usize) -> Self {
        Marks((0..n.div_ceil(64)).map(|_| AtomicU64::new(0)).collect())
    }

    /// Marks point `i`.
    #[inline]
    pub fn mark(&self, i: usize) {
        let (w, bit) = (&self.0[i >> 6], 1u64 << (i & 63));
        // most points are marked by several triangles: read before the locked write
        if w.load(Ordering::Relaxed) & bit == 0 {
            w.fetch_or(bit, Ordering::Relaxed);
        }
    }
}

/// The marked points' values, found by index.
pub struct ClipTable {
    /// Bit `i % 64` of word `i / 64`: point `i` is held.
    words: Vec<u64>,
    /// Per word, the points held before it.
    ranks: Vec<u64>,
    /// The points held, in index order.
    points: Vec<[f64; 4]>,
}

impl ClipTable {
    /// The table of the points `marks` holds, point `i` being `at(i)`.
    pub fn new(marks: Marks, at: impl Fn(usize) -> [f64; 4] + Sync) -> Self {
        let words: Vec<u64> = marks.0.into_iter().map(AtomicU64::into_inner).collect();
        let mut ranks = Vec::with_capacity(words.len());
        let mut held = 0u64;
        for w in &words {
            ranks.push(held);
            held += u64::from(w.count_ones());
        }
        // the points of each run of words computed into their place, in parallel
        let mut points = vec![[0.0; 4]; held as usize];
        let mut parts = Vec::new();
        let mut rest = &mut points[..];
        for (ci, run) in words.chunks(RUN).enumerate() {
            let n: u32 = run.iter().map(|w| w.count_ones()).sum();
            let (part, later) = rest.split_at_mut(n as usize);
            parts.push((ci * RUN, run, part));
            rest = later;
        }
        parts.into_par_iter().for_each(|(w0, run, part)| {
            let all = run
                .iter()
                .enumerate()
                .flat_map(|(j, &w)| Bits(w).map(move |b| (w0 + j) * 64 + b));
            for (p, i) in part.iter_mut().zip(all) {
                *p = at(i);
            }
        });
        ClipTable {
            words,
            ranks,
            points,
        }
    }

    /// Point `i`, None when it is not marked (or past the table).
    #[inline]
    pub fn get(&self, i: usize) -> Option<[f64; 4]> {
        let w = i >> 6;
        let word = *self.words.get(w)?;
        if word >> (i & 63) & 1 == 0 {
            return None;
        }
        let below = word & ((1u64 << (i & 63)) - 1);
        Some(self.points[(self.ranks[w] + u64::from(below.count_ones())) as usize])
    }
}

/// The set bits of a word, lowest first.
struct Bits(u64);

impl Iterator for Bits {
    type Item = usize;

    fn next(&mut self) -> Option<usize> {
        if self.0 == 0 {
            return None;
        }
        let b = self.0.trailing_zeros() as usize;
        self.0 &= self.0 - 1;
        Some(b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_table_holds_the_marked_points_and_finds_each_by_its_index() {
        let n = 1000;
        let value = |i: usize| [i as f64, -(i as f64), 0.5 * i as f64, 1.0];
        let marks = Marks::new(n);
        let picked: Vec<usize> = (0..n).filter(|i| i % 7 == 0 || i % 64 == 63).collect();
        picked.par_iter().for_each(|&i| marks.mark(i));
        picked.iter().for_each(|&i| marks.mark(i)); // twice: still once
        let t = ClipTable::new(marks, value);
        assert_eq!(t.points.len(), picked.len());
        for i in 0..n + 200 {
            // a marked point's value; None for the others and past the table
            let want = picked.contains(&i).then(|| value(i));
            assert_eq!(t.get(i), want, "point {i}");
        }
    }
}
