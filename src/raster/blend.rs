//! The transparent pass: per-sample fragment lists composited over the opaque result.
//!
//! `Blend::Exact` sorts each sample's fragments by depth (ties broken by colour, id and
//! velocity, so the result does not depend on the submission order at all) and composites them
//! back to front with the premultiplied `over` operator. A sample keeps at most
//! [`FRAGMENT_CAP`] fragments in its list; the ones after go to the sample's k-buffer
//! ([`Spill`]), which keeps the nearest [`FRAGMENT_CAP`] of them exactly and merges every
//! farther one into one approximate layer ([`Tail`]). The memory of a tile is then bounded
//! whatever the depth complexity, the result is exact for every sample with at most
//! [`FRAGMENT_CAP`] fragments, and a sample with more gets its nearest [`FRAGMENT_CAP`]
//! composited exactly over the merged layer (its alpha exact, its colour an alpha-weighted
//! mean; the tile counts these samples).
//!
//! `Blend::Unsorted` does what z-buffer hardware without sorting did (the motion-volume paper's
//! behaviour), so that the error of not sorting can be measured: fragments in submission order,
//! each depth-tested against the depth the fragments before it wrote (and the opaque surface),
//! composited over when nearer and writing its depth, dropped when not. It needs no list: each
//! fragment is composited as it comes.
use super::fragment::far_to_near;
pub use super::fragment::{Frag, FRAGMENT_CAP};
use super::kbuffer::{merge_far_to_near, Spill, Tail};
use std::cmp::Ordering;

/// The per-sample result after both passes (in this field order: the resolve reads it as
/// eight floats).
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct Sample {
    pub rgba: [f32; 4],
    /// 1/w of the nearest surface with alpha > 0 (0 for background).
    pub invw: f32,
    pub id: i32,
    pub velocity: [f32; 2],
}

impl Sample {
    pub const BACKGROUND: Sample = Sample {
        rgba: [0.0; 4],
        invw: 0.0,
        id: -1,
        velocity: [0.0; 2],
    };
}

/// Premultiplied `src over dst`.
#[inline]
pub fn over(src: [f32; 4], dst: [f32; 4]) -> [f32; 4] {
    let k = 1.0 - src[3];
    [
        src[0] + k * dst[0],
        src[1] + k * dst[1],
        src[2] + k * dst[2],
        src[3] + k * dst[3],
    ]
}

/// Reusable buffers of the transparent pass.
///
/// Fragments are pushed in submission order with a per-sample count. Most samples of a typical
/// frame hold one transparent fragment (a convex surface drawn with back faces culled) or two
/// (its front and back): those are composited straight from the list, and only the fragments of
/// samples holding more are grouped per sample (in submission order) and sorted. A sample's
/// fragments past [`FRAGMENT_CAP`] go to its [`Spill`], so the lists hold at most
/// [`FRAGMENT_CAP`] fragments a sample. Allocations are fallible: a refused one marks the lists
/// `refused` (the bytes) and drops the fragment, and the caller fails the frame.
#[derive(Default)]
pub struct FragLists {
    frags: Vec<Frag>,
    /// Fragments per tile sample in `frags`; `SEEN` marks a sample whose first fragment was met
    /// while compositing (a pair's first, or a group given its slots). With `Blend::Unsorted`,
    /// whether a fragment of the sample was composited.
    count: Vec<u32>,
    /// The fragments of samples with several, grouped per sample.
    sorted: Vec<Frag>,
    /// A pair's first fragment in `frags`, or the next free slot in `sorted` of a sample being
    /// grouped (valid once `SEEN`).
    next: Vec<u32>,
    /// (sample, first slot, fragment count) of each group in `sorted`.
    groups: Vec<(u32, u32, u32)>,
    /// Per tile sample: the index of its spill in `spills`, or `NO_SPILL`.
    spill_of: Vec<u32>,
    /// Spills of this tile (the first `n_spills`) and spare ones kept with their buffers.
    spills: Vec<Spill>,
    n_spills: usize,
    /// A spilled sample's list and kept fragments merged far to near.
    merged: Vec<Frag>,
    /// Bytes of an allocation the system refused in this tile (0: none).
    pub refused: u64,
}

/// Spills a thread keeps (with their buffers) between tiles.
const KEEP_SPILLS: usize = 256;

/// Flag of `FragLists::count` for a sample whose slots in `sorted` are assigned.
const SEEN: u32 = 1 << 31;

/// `FragLists::spill_of` of a sample without a spill.
const NO_SPILL: u32 = u32::MAX;

impl FragLists {
    /// Empties the lists for a tile of `n` samples.
    pub fn clear(&mut self, n: usize) {
        self.frags.clear();
        self.count.clear();
        self.count.resize(n, 0);
        self.release_spills();
        if self.spill_of.len() != n {
            self.spill_of.clear();
            self.spill_of.resize(n, NO_SPILL);
        }
        self.refused = 0;
    }

    /// Fragments the list has room for (tests: it never holds more than the cap a sample).
    #[cfg(test)]
    pub fn held_capacity(&self) -> usize {
        self.frags.capacity()
    }

    /// Gives back the spills in use (their samples have none again).
    fn release_spills(&mut self) {
        for sp in &self.spills[..self.n_spills] {
            if let Some(slot) = self.spill_of.get_mut(sp.sample as usize) {
                *slot = NO_SPILL;
            }
        }
        self.n_spills = 0;
    }

    /// Appends a fragment of `Blend::Exact` (fragments arrive in submission order): to its
    /// sample's list, or to its spill when the list holds [`FRAGMENT_CAP`] already.
    #[inline(always)]
    pub fn push(&mut self, f: Frag) {
        let s = f.sample as usize;
        let c = self.count[s];
        if c >= FRAGMENT_CAP {
            self.spill(s, f);
            return;
        }
        if self.frags.len() == self.frags.capacity() && !self.grow() {
            return;
        }
        self.count[s] = c + 1;
        self.frags.push(f);
    }

    /// Room for more fragments (at most [`FRAGMENT_CAP`] a sample), or false after marking the
    /// lists `refused`.
    #[cold]
    fn grow(&mut self) -> bool {
        let limit = self.count.len() * FRAGMENT_CAP as usize;
        let more = self.frags.len().max(1024).min(limit - self.frags.len());
        let ok = self.refused == 0 && self.frags.try_reserve(more).is_ok();
        if !ok {
            self.refuse::<Frag>(self.frags.len() + more);
        }
        ok
    }

    #[cold]
    fn refuse<T>(&mut self, elements: usize) {
        let bytes = (elements * std::mem::size_of::<T>()) as u64;
        self.refused = self.refused.max(bytes.max(1));
    }

    /// A fragment of a sample whose list is full: into the sample's spill (made on its first).
    #[cold]
    fn spill(&mut self, s: usize, f: Frag) {
        let mut i = self.spill_of[s] as usize;
        if i == NO_SPILL as usize {
            if self.refused != 0 {
                return;
            }
            if self.n_spills == self.spills.len() {
                if self.spills.try_reserve(1).is_err() {
                    return self.refuse::<Spill>(self.spills.len() + 1);
                }
                self.spills.push(Spill::default());
            }
            let cap = FRAGMENT_CAP as usize;
            let sp = &mut self.spills[self.n_spills];
            if sp.kept.capacity() < cap && sp.kept.try_reserve_exact(cap).is_err() {
                return self.refuse::<Frag>(cap);
            }
            if self.merged.capacity() < 2 * cap && self.merged.try_reserve_exact(2 * cap).is_err() {
                return self.refuse::<Frag>(2 * cap);
            }
            sp.sample = s as u32;
            sp.kept.clear();
            sp.tail = Tail::default();
            i = self.n_spills;
            self.spill_of[s] = i as u32;
            self.n_spills += 1;
        }
        self.spills[i].add(f);
    }

    /// Composites a fragment of `Blend::Unsorted` over its sample in `samples` (the opaque
    /// result) at once: the sample's first passes (it passed the opaque surface's depth test),
    /// each later one when strictly nearer than the last composited, whose depth it then writes.
    #[inline(always)]
    pub fn blend_unsorted(&mut self, samples: &mut [Sample], f: Frag) {
        let s = f.sample as usize;
        let sample = &mut samples[s];
        if self.count[s] == 0 || f.invw > sample.invw {
            self.count[s] = 1;
            sample.rgba = over(f.shaded.rgba, sample.rgba);
            sample.invw = f.invw;
            sample.id = f.shaded.id;
            sample.velocity = f.shaded.velocity;
        }
    }

    /// Releases the memory beyond what a thread keeps between tiles (the lists themselves are
    /// bounded by [`FRAGMENT_CAP`] fragments a sample).
    pub fn trim(&mut self) {
        self.release_spills();
        if self.spills.len() > KEEP_SPILLS {
            self.spills.truncate(KEEP_SPILLS);
            self.spills.shrink_to_fit();
        }
    }

    /// Composites the pushed fragments (`Blend::Exact`) over `samples` (the opaque result, the
    /// `n` samples of `clear`). Returns the number of samples whose farthest fragments were
    /// merged (those past [`FRAGMENT_CAP`]).
    pub fn composite(&mut self, samples: &mut [Sample]) -> u64 {
        if self.frags.is_empty() {
            return 0;
        }
        debug_assert_eq!(samples.len(), self.count.len());
        // A sample's only fragment needs no list; a sample's two fragments (the front and back
        // of a closed surface) are composited when the second comes, the first found through
        // `next`. Only samples holding three or more are grouped.
        self.next.resize(samples.len(), 0);
        let mut several = 0usize;
        for (i, f) in self.frags.iter().enumerate() {
            let s = f.sample as usize;
            match self.count[s] {
                1 => {
                    let sample = &mut samples[s];
                    sample.rgba = over(f.shaded.rgba, sample.rgba);
                    sample.invw = f.invw;
                    sample.id = f.shaded.id;
                    sample.velocity = f.shaded.velocity;
                }
                2 => {
                    self.count[s] = 2 | SEEN;
                    self.next[s] = i as u32;
                }
                c if c == 2 | SEEN => {
                    composite_pair(&self.frags[self.next[s] as usize], f, &mut samples[s]);
                }
                _ => several += 1,
            }
        }
        if several == 0 {
            return 0;
        }
        // Group the others per sample in submission order: a sample gets its slots when its
        // first fragment comes (groups in order of first appearance; samples are independent).
        // `several` is at most the list's length, itself at most FRAGMENT_CAP a sample.
        self.sorted.clear();
        if self.sorted.try_reserve(several).is_err() {
            self.refuse::<Frag>(several);
            return 0;
        }
        self.sorted.resize(several, Frag::default());
        self.groups.clear();
        let mut cursor = 0u32;
        for f in &self.frags {
            let s = f.sample as usize;
            let c = self.count[s];
            if c & !SEEN <= 2 {
                continue;
            }
            if c & SEEN == 0 {
                self.groups.push((f.sample, cursor, c));
                self.next[s] = cursor;
                cursor += c;
                self.count[s] = c | SEEN;
            }
            let slot = &mut self.next[s];
            self.sorted[*slot as usize] = *f;
            *slot += 1;
        }
        let mut approximated = 0u64;
        for &(s, lo, len) in &self.groups {
            let list = &mut self.sorted[lo as usize..(lo + len) as usize];
            insertion_sort(list);
            let sample = &mut samples[s as usize];
            let mut c = sample.rgba;
            let spill = self.spill_of[s as usize];
            let list: &[Frag] = if spill == NO_SPILL {
                list
            } else {
                // The list (its sample's first FRAGMENT_CAP fragments) and the spill's nearest:
                // the nearest FRAGMENT_CAP of both are the sample's nearest, composited exactly;
                // the rest are farther than every one of them, merged with the spill's tail.
                approximated += 1;
                let sp = &mut self.spills[spill as usize];
                sp.kept.sort_unstable_by(far_to_near);
                merge_far_to_near(list, &sp.kept, &mut self.merged);
                let cut = self.merged.len() - FRAGMENT_CAP as usize;
                let mut tail = sp.tail;
                for f in &self.merged[..cut] {
                    tail.add(f);
                }
                c = over(tail.rgba(), c);
                &self.merged[cut..]
            };
            let mut nearest = list[0];
            for f in list.iter() {
                c = over(f.shaded.rgba, c);
                if f.invw > nearest.invw {
                    nearest = *f;
                }
            }
            sample.rgba = c;
            // Every fragment here passed the depth test, so it is nearer than the opaque surface.
            sample.invw = nearest.invw;
            sample.id = nearest.shaded.id;
            sample.velocity = nearest.shaded.velocity;
        }
        approximated
    }
}

/// The exact composite of a sample's two fragments `a` and `b` (in submission order) without
/// copying them: sorting the pair far to near (`far_to_near`) and compositing it, op for op.
#[inline(always)]
fn composite_pair(a: &Frag, b: &Frag, sample: &mut Sample) {
    let (first, second) = match far_to_near(a, b) {
        Ordering::Greater => (b, a),
        _ => (a, b),
    };
    sample.rgba = over(second.shaded.rgba, over(first.shaded.rgba, sample.rgba));
    // The list's rule: the nearest is the first unless a later one has a greater 1/w.
    let nearest = [first, second][(second.invw > first.invw) as usize];
    sample.invw = nearest.invw;
    sample.id = nearest.shaded.id;
    sample.velocity = nearest.shaded.velocity;
}

/// Stable insertion sort, far to near: lists are short (a few layers per sample).
fn insertion_sort(list: &mut [Frag]) {
    if list.len() > 32 {
        list.sort_by(far_to_near);
        return;
    }
    for i in 1..list.len() {
        let mut j = i;
        while j > 0 && far_to_near(&list[j - 1], &list[j]) == Ordering::Greater {
            list.swap(j - 1, j);
            j -= 1;
        }
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::raster::options::Blend;
    use crate::raster::shade::Shaded;

    pub(in crate::raster) fn frag(sample: u32, invw: f32, a: f32, id: i32) -> Frag {
        Frag {
            sample,
            invw,
            shaded: Shaded {
                rgba: [a * 0.5, a * 0.25, 0.0, a],
                id,
                velocity: [0.0; 2],
            },
        }
    }

    #[test]
    fn exact_blending_ignores_submission_order() {
        let a = vec![
            frag(0, 0.5, 0.3, 1),
            frag(0, 0.2, 0.6, 2),
            frag(0, 0.9, 0.5, 3),
            frag(1, 0.1, 0.5, 4),
        ];
        let mut b = a.clone();
        b.reverse();
        let run = |frags: Vec<Frag>| {
            let mut l = FragLists::default();
            l.clear(2);
            for f in frags {
                l.push(f);
            }
            let mut s = [Sample::BACKGROUND; 2];
            l.composite(&mut s);
            s
        };
        let (sa, sb) = (run(a), run(b));
        for k in 0..2 {
            assert_eq!(sa[k].rgba, sb[k].rgba);
            assert_eq!(sa[k].id, sb[k].id);
        }
        assert_eq!(
            sa[0].id, 3,
            "the nearest fragment (largest 1/w) names the sample"
        );
        // Numpy-free twin: back to front over by hand.
        let mut want = [0.0f32; 4];
        for (w, al) in [(0.2f32, 0.6f32), (0.5, 0.3), (0.9, 0.5)] {
            let _ = w;
            want = over([al * 0.5, al * 0.25, 0.0, al], want);
        }
        assert_eq!(sa[0].rgba, want);
    }

    #[test]
    fn unsorted_blending_tests_and_writes_depth_in_submission_order() {
        let run = |frags: Vec<Frag>| {
            let mut l = FragLists::default();
            l.clear(1);
            let mut s = [Sample::BACKGROUND; 1];
            for f in frags {
                l.blend_unsorted(&mut s, f);
            }
            s[0]
        };
        let half = [0.25, 0.125, 0.0, 0.5];
        // far first, then near: both drawn, in that order (as sorted)
        let s = run(vec![frag(0, 0.2, 0.5, 2), frag(0, 0.9, 0.5, 1)]);
        assert_eq!(s.rgba, over(half, over(half, [0.0; 4])));
        assert_eq!((s.id, s.invw), (1, 0.9));
        // near first: it writes its depth and the far one drawn later fails the test
        let s = run(vec![frag(0, 0.9, 0.5, 1), frag(0, 0.2, 0.5, 2)]);
        assert_eq!(s.rgba, over(half, [0.0; 4]));
        assert_eq!((s.id, s.invw), (1, 0.9));
        // three layers: near, far (dropped), nearer (drawn)
        let s = run(vec![
            frag(0, 0.5, 0.5, 1),
            frag(0, 0.2, 0.5, 2),
            frag(0, 0.7, 0.5, 3),
        ]);
        assert_eq!(s.rgba, over(half, over(half, [0.0; 4])));
        assert_eq!(s.id, 3);
    }

    /// Per sample on its own: its fragments in submission order, sorted (exact), composited.
    pub(in crate::raster) fn reference(frags: &[Frag], samples: &mut [Sample], blend: Blend) {
        for (s, sample) in samples.iter_mut().enumerate() {
            let mut list: Vec<Frag> = frags
                .iter()
                .filter(|f| f.sample as usize == s)
                .copied()
                .collect();
            if list.is_empty() {
                continue;
            }
            if blend == Blend::Exact {
                list.sort_by(far_to_near);
            }
            let mut nearest = list[0];
            for (k, f) in list.iter().enumerate() {
                if blend == Blend::Unsorted && k > 0 && f.invw <= nearest.invw {
                    continue; // fails the depth test against what was written before
                }
                sample.rgba = over(f.shaded.rgba, sample.rgba);
                if k == 0 || f.invw > nearest.invw {
                    nearest = *f;
                }
            }
            sample.invw = nearest.invw;
            sample.id = nearest.shaded.id;
            sample.velocity = nearest.shaded.velocity;
        }
    }

    #[test]
    fn lone_fragments_and_lists_composite_like_each_sample_on_its_own() {
        // Tiles mixing empty samples, samples with one fragment (composited straight from the
        // list) and samples with several (grouped and sorted), depth ties included, over
        // opaque samples; the lists are reused across tiles as a thread's scratch is.
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = |m: u32| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % u64::from(m)) as u32
        };
        let mut l = FragLists::default();
        let (mut lone, mut listed, mut spilled) = (0, 0, 0);
        for round in 0..300 {
            let n = 1 + next(200) as usize;
            let count = next(3 * n as u32);
            let frags: Vec<Frag> = (0..count)
                .map(|_| {
                    // few samples get most fragments in some rounds, all samples in others
                    let s = if round % 3 == 0 {
                        next(n as u32) % 7
                    } else {
                        next(n as u32)
                    };
                    let mut f = frag(
                        s.min(n as u32 - 1),
                        0.1 * (1 + next(4)) as f32,
                        0.05 * (1 + next(19)) as f32,
                        next(5) as i32,
                    );
                    f.shaded.velocity = [next(3) as f32, 0.0];
                    f
                })
                .collect();
            let start: Vec<Sample> = (0..n)
                .map(|i| Sample {
                    rgba: [0.1 * (i % 5) as f32, 0.2, 0.3, 1.0],
                    invw: 0.05,
                    id: 100 + i as i32,
                    velocity: [0.0, 1.0],
                })
                .collect();
            for blend in [Blend::Exact, Blend::Unsorted] {
                let mut got = start.clone();
                l.clear(n);
                for f in &frags {
                    match blend {
                        Blend::Exact => l.push(*f),
                        Blend::Unsorted => l.blend_unsorted(&mut got, *f),
                    }
                }
                let approximated = if blend == Blend::Exact {
                    l.composite(&mut got)
                } else {
                    0
                };
                let mut want = start.clone();
                reference(&frags, &mut want, blend);
                let mut over_cap = 0;
                for s in 0..n {
                    let k = frags.iter().filter(|f| f.sample as usize == s).count();
                    lone += usize::from(k == 1);
                    listed += usize::from(k > 1);
                    let (g, w) = (got[s], want[s]);
                    // the nearest fragment names the sample, merged or not
                    assert_eq!((g.invw.to_bits(), g.id), (w.invw.to_bits(), w.id));
                    assert_eq!(g.velocity.map(f32::to_bits), w.velocity.map(f32::to_bits));
                    if blend == Blend::Exact && k > FRAGMENT_CAP as usize {
                        over_cap += 1;
                        let list: Vec<Frag> = frags
                            .iter()
                            .filter(|f| f.sample as usize == s)
                            .copied()
                            .collect();
                        assert_within_merge_bound(&list, &start[s], &g, &w);
                        continue;
                    }
                    assert_eq!(
                        g.rgba.map(f32::to_bits),
                        w.rgba.map(f32::to_bits),
                        "round {round} sample {s}"
                    );
                }
                assert_eq!(approximated, over_cap);
                spilled += over_cap;
            }
        }
        assert!(
            lone > 1000 && listed > 1000 && spilled > 100,
            "every path must be exercised: {lone} {listed} {spilled}"
        );
    }

    /// `got` (a sample with more than FRAGMENT_CAP fragments `list` over `start`) against the
    /// exact `want`: alpha the same up to rounding (the merged layer's alpha is exact), each
    /// colour channel within what reordering the merged fragments can change, the spread of
    /// their straight colours times the merged alpha times what the nearest let through.
    pub(in crate::raster) fn assert_within_merge_bound(
        list: &[Frag],
        start: &Sample,
        got: &Sample,
        want: &Sample,
    ) {
        let mut sorted = list.to_vec();
        sorted.sort_by(far_to_near);
        let (tail, kept) = sorted.split_at(sorted.len() - FRAGMENT_CAP as usize);
        let through: f32 = kept.iter().map(|f| 1.0 - f.shaded.rgba[3]).product();
        let merged_alpha = 1.0 - tail.iter().map(|f| 1.0 - f.shaded.rgba[3]).product::<f32>();
        assert!(
            (got.rgba[3] - want.rgba[3]).abs() <= 1e-5,
            "{got:?} {want:?}"
        );
        for ch in 0..3 {
            let straight = tail.iter().map(|f| f.shaded.rgba[ch] / f.shaded.rgba[3]);
            let lo = straight.clone().fold(f32::INFINITY, f32::min);
            let hi = straight.fold(f32::NEG_INFINITY, f32::max);
            let bound = through * merged_alpha * (hi - lo) + 1e-5;
            let err = (got.rgba[ch] - want.rgba[ch]).abs();
            assert!(err <= bound, "channel {ch}: {err} > {bound} ({start:?})");
        }
    }
}
