//! The transparent pass: per-sample fragment lists composited over the opaque result.
//!
//! `Blend::Exact` sorts each sample's fragments by depth (ties broken by colour, id and
//! velocity, so the result does not depend on the submission order at all) and composites them
//! back to front with the premultiplied `over` operator. `Blend::Unsorted` does what z-buffer
//! hardware without sorting did (the motion-volume paper's behaviour), so that the error of not
//! sorting can be measured: fragments in submission order, each depth-tested against the depth
//! the fragments before it wrote (and the opaque surface), composited over when nearer and
//! writing its depth, dropped when not.
use super::options::Blend;
use super::shade::Shaded;
use std::cmp::Ordering;

/// One transparent fragment in a tile: the tile-local sample, 1/w, and its shading.
#[derive(Clone, Copy, Debug, Default)]
pub struct Frag {
    pub sample: u32,
    pub invw: f32,
    pub shaded: Shaded,
}

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

/// Total order on fragments of one sample, far to near, independent of submission order.
#[inline(always)]
fn far_to_near(a: &Frag, b: &Frag) -> Ordering {
    a.invw
        .total_cmp(&b.invw)
        .then_with(|| {
            let ka = a.shaded.rgba.map(f32::to_bits);
            let kb = b.shaded.rgba.map(f32::to_bits);
            ka.cmp(&kb)
        })
        .then(a.shaded.id.cmp(&b.shaded.id))
        .then_with(|| {
            let ka = a.shaded.velocity.map(f32::to_bits);
            let kb = b.shaded.velocity.map(f32::to_bits);
            ka.cmp(&kb)
        })
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
/// samples holding more are grouped per sample (in submission order) and sorted.
#[derive(Default)]
pub struct FragLists {
    frags: Vec<Frag>,
    /// Fragments per tile sample; `SEEN` marks a sample whose first fragment was met (a pair's
    /// first, or a group given its slots).
    count: Vec<u32>,
    /// The fragments of samples with several, grouped per sample.
    sorted: Vec<Frag>,
    /// A pair's first fragment in `frags`, or the next free slot in `sorted` of a sample being
    /// grouped (valid once `SEEN`).
    next: Vec<u32>,
    /// (sample, first slot, fragment count) of each group in `sorted`.
    groups: Vec<(u32, u32, u32)>,
}

/// Fragments a thread keeps room for between tiles (36 bytes each, twice): a tile of extreme
/// depth complexity may grow the lists further, and they are released after it.
const KEEP_FRAGS: usize = 1 << 18;

/// Flag of `FragLists::count` for a sample whose slots in `sorted` are assigned.
const SEEN: u32 = 1 << 31;

impl FragLists {
    /// Empties the lists for a tile of `n` samples.
    pub fn clear(&mut self, n: usize) {
        self.frags.clear();
        self.count.clear();
        self.count.resize(n, 0);
    }

    /// Appends a fragment (fragments arrive in submission order).
    #[inline(always)]
    pub fn push(&mut self, f: Frag) {
        self.count[f.sample as usize] += 1;
        self.frags.push(f);
    }

    /// Releases the lists' memory beyond `KEEP_FRAGS` fragments (kept buffers stay bounded).
    pub fn trim(&mut self) {
        if self.frags.capacity() > KEEP_FRAGS || self.sorted.capacity() > KEEP_FRAGS {
            self.frags = Vec::new();
            self.sorted = Vec::new();
        }
    }

    /// Composites the fragments over `samples` (the opaque result, the `n` samples of `clear`).
    pub fn composite(&mut self, samples: &mut [Sample], blend: Blend) {
        if self.frags.is_empty() {
            return;
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
                    composite_pair(
                        &self.frags[self.next[s] as usize],
                        f,
                        &mut samples[s],
                        blend,
                    );
                }
                _ => several += 1,
            }
        }
        if several == 0 {
            return;
        }
        // Group the others per sample in submission order: a sample gets its slots when its
        // first fragment comes (groups in order of first appearance; samples are independent).
        self.sorted.clear();
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
        for &(s, lo, len) in &self.groups {
            let list = &mut self.sorted[lo as usize..(lo + len) as usize];
            composite_list(list, &mut samples[s as usize], blend);
        }
    }
}

/// `composite_list` of two fragments `a` and `b` (in submission order), without copying them:
/// the same order (`far_to_near`, which first compares 1/w) and the same operations.
#[inline(always)]
fn composite_pair(a: &Frag, b: &Frag, sample: &mut Sample, blend: Blend) {
    let (first, second) = match blend {
        Blend::Exact if far_to_near(a, b) == Ordering::Greater => (b, a),
        _ => (a, b),
    };
    let mut c = over(first.shaded.rgba, sample.rgba);
    let mut nearest = first;
    if blend == Blend::Exact || second.invw > first.invw {
        c = over(second.shaded.rgba, c);
    }
    if second.invw > first.invw {
        nearest = second;
    }
    sample.rgba = c;
    sample.invw = nearest.invw;
    sample.id = nearest.shaded.id;
    sample.velocity = nearest.shaded.velocity;
}

/// Composites one sample's fragments (in submission order, two or more) over it: sorted far
/// to near for `Exact`; for `Unsorted` each later fragment drawn only when nearer than the
/// ones before it wrote.
#[inline]
fn composite_list(list: &mut [Frag], sample: &mut Sample, blend: Blend) {
    if blend == Blend::Exact {
        insertion_sort(list);
    }
    let mut c = sample.rgba;
    let mut nearest = list[0];
    if blend == Blend::Unsorted {
        // the first fragment passed the opaque surface's test; each later one is tested
        // against the depth the ones before it wrote (a strictly nearer one passes)
        for (k, f) in list.iter().enumerate() {
            if k == 0 || f.invw > nearest.invw {
                c = over(f.shaded.rgba, c);
                nearest = *f;
            }
        }
    } else {
        for f in list.iter() {
            c = over(f.shaded.rgba, c);
            if f.invw > nearest.invw {
                nearest = *f;
            }
        }
    }
    sample.rgba = c;
    // Every fragment here passed the depth test, so it is nearer than the opaque surface.
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
mod tests {
    use super::*;

    fn frag(sample: u32, invw: f32, a: f32, id: i32) -> Frag {
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
            l.composite(&mut s, Blend::Exact);
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
            for f in frags {
                l.push(f);
            }
            let mut s = [Sample::BACKGROUND; 1];
            l.composite(&mut s, Blend::Unsorted);
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
    fn reference(frags: &[Frag], samples: &mut [Sample], blend: Blend) {
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
        let (mut lone, mut listed) = (0, 0);
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
                    l.push(*f);
                }
                l.composite(&mut got, blend);
                let mut want = start.clone();
                reference(&frags, &mut want, blend);
                for s in 0..n {
                    let k = frags.iter().filter(|f| f.sample as usize == s).count();
                    lone += usize::from(k == 1);
                    listed += usize::from(k > 1);
                    let (g, w) = (got[s], want[s]);
                    assert_eq!(
                        g.rgba.map(f32::to_bits),
                        w.rgba.map(f32::to_bits),
                        "round {round} sample {s}"
                    );
                    assert_eq!((g.invw.to_bits(), g.id), (w.invw.to_bits(), w.id));
                    assert_eq!(g.velocity.map(f32::to_bits), w.velocity.map(f32::to_bits));
                }
            }
        }
        assert!(
            lone > 1000 && listed > 1000,
            "both paths must be exercised: {lone} {listed}"
        );
    }
}
