//! The k-buffer of the exact transparent pass: what a sample keeps of the fragments past its
//! list's [`FRAGMENT_CAP`] (`blend.rs`). The nearest [`FRAGMENT_CAP`] of them stay exact in a
//! heap whose root is the farthest; every farther one is merged into one layer ([`Tail`]) whose
//! alpha is exact and whose colour is their alpha-weighted mean. A sample's memory is then
//! bounded whatever its depth complexity, and each fragment past the cap costs
//! `log2(FRAGMENT_CAP)` steps.
use super::fragment::{far_to_near, Frag, FRAGMENT_CAP};
use std::cmp::Ordering;

/// The farthest fragments of a sample past the cap, merged into one layer: its alpha is exactly
/// what compositing them in any order gives (`1 - prod(1 - a)`), its colour their
/// premultiplied colours' alpha-weighted mean scaled to that alpha.
#[derive(Clone, Copy, Debug)]
pub(super) struct Tail {
    rgb: [f64; 3],
    alpha: f64,
    transmit: f64,
}

impl Default for Tail {
    fn default() -> Self {
        Tail {
            rgb: [0.0; 3],
            alpha: 0.0,
            transmit: 1.0,
        }
    }
}

impl Tail {
    pub(super) fn add(&mut self, f: &Frag) {
        let c = f.shaded.rgba;
        for k in 0..3 {
            self.rgb[k] += f64::from(c[k]);
        }
        self.alpha += f64::from(c[3]);
        self.transmit *= 1.0 - f64::from(c[3]);
    }

    /// The merged layer, premultiplied.
    pub(super) fn rgba(&self) -> [f32; 4] {
        if self.alpha <= 0.0 {
            return [0.0; 4];
        }
        let a = 1.0 - self.transmit;
        let k = a / self.alpha;
        [
            (self.rgb[0] * k) as f32,
            (self.rgb[1] * k) as f32,
            (self.rgb[2] * k) as f32,
            a as f32,
        ]
    }
}

/// The k-buffer of a sample past the cap: the nearest [`FRAGMENT_CAP`] of the fragments that
/// came after its list was full, in a heap whose root is the farthest (so a nearer fragment
/// replaces it in `log2(FRAGMENT_CAP)` steps), and the farther ones merged.
#[derive(Debug, Default)]
pub(super) struct Spill {
    /// The tile sample it belongs to.
    pub(super) sample: u32,
    /// The nearest fragments, a heap (a parent is never nearer than its children).
    pub(super) kept: Vec<Frag>,
    /// The farther ones, merged.
    pub(super) tail: Tail,
}

impl Spill {
    /// Adds a fragment: into the heap while it has room or when nearer than its farthest
    /// (which then goes to the tail), else to the tail.
    pub(super) fn add(&mut self, f: Frag) {
        let heap = &mut self.kept;
        if heap.len() < FRAGMENT_CAP as usize {
            // sift up: a parent is never nearer than its children
            heap.push(f);
            let mut i = heap.len() - 1;
            while i > 0 {
                let p = (i - 1) / 2;
                if far_to_near(&heap[i], &heap[p]) != Ordering::Less {
                    break;
                }
                heap.swap(i, p);
                i = p;
            }
            return;
        }
        if far_to_near(&f, &heap[0]) != Ordering::Greater {
            self.tail.add(&f); // no nearer than the farthest kept
            return;
        }
        self.tail.add(&heap[0]);
        heap[0] = f;
        // sift down
        let n = heap.len();
        let mut i = 0;
        loop {
            let (l, r) = (2 * i + 1, 2 * i + 2);
            let mut far = i;
            if l < n && far_to_near(&heap[l], &heap[far]) == Ordering::Less {
                far = l;
            }
            if r < n && far_to_near(&heap[r], &heap[far]) == Ordering::Less {
                far = r;
            }
            if far == i {
                break;
            }
            heap.swap(i, far);
            i = far;
        }
    }
}

/// `a` and `b` (each sorted far to near) merged far to near into `out`.
pub(super) fn merge_far_to_near(a: &[Frag], b: &[Frag], out: &mut Vec<Frag>) {
    out.clear();
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        if far_to_near(&b[j], &a[i]) == Ordering::Less {
            out.push(b[j]);
            j += 1;
        } else {
            out.push(a[i]);
            i += 1;
        }
    }
    out.extend_from_slice(&a[i..]);
    out.extend_from_slice(&b[j..]);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::blend::tests::{assert_within_merge_bound, frag as listed, reference};
    use crate::raster::blend::{FragLists, Sample};
    use crate::raster::options::Blend;
    use crate::raster::shade::Shaded;

    fn frag(invw: f32, a: f32, g: f32) -> Frag {
        Frag {
            sample: 0,
            invw,
            shaded: Shaded {
                rgba: [0.5 * a, g * a, 0.0, a],
                id: (invw * 1000.0) as i32,
                velocity: [0.0; 2],
            },
        }
    }

    #[test]
    fn the_heap_keeps_the_nearest_and_the_tail_merges_the_rest_with_exact_alpha() {
        let cap = FRAGMENT_CAP as usize;
        let n = 5 * cap;
        // in an order that makes every kind of step happen: nearer, farther, ties
        let frags: Vec<Frag> = (0..n)
            .map(|i| (i * 37) % n)
            .map(|k| {
                frag(
                    0.001 * (k / 2 + 1) as f32,
                    0.01 + 0.001 * (k % 9) as f32,
                    0.1 * (k % 4) as f32,
                )
            })
            .collect();
        let mut sp = Spill::default();
        for f in &frags {
            sp.add(*f);
        }
        let mut sorted = frags.clone();
        sorted.sort_by(far_to_near);
        let mut kept = sp.kept.clone();
        kept.sort_by(far_to_near);
        let want = &sorted[n - cap..];
        for (a, b) in kept.iter().zip(want) {
            assert_eq!(far_to_near(a, b), Ordering::Equal);
        }
        let mut exact = Tail::default();
        for f in &sorted[..n - cap] {
            exact.add(f);
        }
        let (got, want) = (sp.tail.rgba(), exact.rgba());
        for k in 0..4 {
            assert!((got[k] - want[k]).abs() < 1e-6, "{got:?} {want:?}");
        }
        let alpha = 1.0
            - sorted[..n - cap]
                .iter()
                .map(|f| 1.0 - f64::from(f.shaded.rgba[3]))
                .product::<f64>();
        assert!((f64::from(got[3]) - alpha).abs() < 1e-6);
        // merging the sorted kept with a list gives one far-to-near order
        let mut out = Vec::new();
        merge_far_to_near(&sorted[..cap], &kept, &mut out);
        assert!(out
            .windows(2)
            .all(|w| far_to_near(&w[0], &w[1]) != Ordering::Greater));
        assert_eq!(out.len(), 2 * cap);
    }

    #[test]
    fn a_deep_sample_keeps_its_nearest_fragments_exactly_and_merges_the_rest() {
        // 200 layers on one sample, submitted in a shuffled order; its neighbour holds
        // FRAGMENT_CAP layers exactly (no spill).
        let cap = FRAGMENT_CAP as usize;
        let mut frags: Vec<Frag> = (0..200)
            .map(|i| {
                let mut f = listed(0, 0.001 * (i + 1) as f32, 0.02 + 0.001 * (i % 7) as f32, i);
                f.shaded.rgba[1] = f.shaded.rgba[3] * (i % 3) as f32 * 0.5;
                f
            })
            .collect();
        frags.extend((0..cap).map(|i| listed(1, 0.01 * (i + 1) as f32, 0.1, i as i32)));
        let mut order: Vec<usize> = (0..frags.len()).collect();
        order.sort_by_key(|&i| (i * 7919) % frags.len());
        let mut l = FragLists::default();
        let start = Sample {
            rgba: [0.0, 0.0, 1.0, 1.0],
            invw: 0.0,
            id: -1,
            velocity: [0.0; 2],
        };
        for _ in 0..2 {
            // twice: the lists and spills are reused as a thread's scratch is
            l.clear(2);
            for &i in &order {
                l.push(frags[i]);
            }
            let mut got = [start; 2];
            assert_eq!(l.composite(&mut got), 1, "only sample 0 is past the cap");
            let shuffled: Vec<Frag> = order.iter().map(|&i| frags[i]).collect();
            let mut want = [start; 2];
            reference(&shuffled, &mut want, Blend::Exact);
            assert_eq!(
                got[1].rgba.map(f32::to_bits),
                want[1].rgba.map(f32::to_bits)
            );
            assert_eq!((got[0].id, got[0].invw), (want[0].id, want[0].invw));
            assert_eq!(got[0].id, 199);
            assert_within_merge_bound(&frags[..200], &start, &got[0], &want[0]);
            // the merged layer is not the exact one: the test's colours make it differ
            assert_ne!(got[0].rgba, want[0].rgba);
        }
        // the lists never held more than FRAGMENT_CAP fragments a sample
        assert!(l.held_capacity() <= 2 * cap);
    }
}
