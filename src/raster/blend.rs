//! The transparent pass: per-sample fragment lists composited over the opaque result.
//!
//! `Blend::Exact` sorts each sample's fragments by depth (ties broken by colour, id and
//! velocity, so the result does not depend on the submission order at all) and composites them
//! back to front with the premultiplied `over` operator. `Blend::Unsorted` composites them in
//! submission order, as z-buffer hardware without sorting does (the motion-volume paper's
//! behaviour), so that the error of not sorting can be measured.
use super::shade::Shaded;
use std::cmp::Ordering;

/// How transparent fragments are composited.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Blend {
    Exact,
    Unsorted,
}

/// One transparent fragment in a tile: the tile-local sample, 1/w, and its shading.
#[derive(Clone, Copy, Debug, Default)]
pub struct Frag {
    pub sample: u32,
    pub invw: f32,
    pub shaded: Shaded,
}

/// The per-sample result after both passes.
#[derive(Clone, Copy, Debug)]
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
#[inline]
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
#[derive(Default)]
pub struct FragLists {
    pub frags: Vec<Frag>,
    sorted: Vec<Frag>,
    start: Vec<u32>,
    next: Vec<u32>,
}

/// Fragments a thread keeps room for between tiles (36 bytes each, twice): a tile of extreme
/// depth complexity may grow the lists further, and they are released after it.
const KEEP_FRAGS: usize = 1 << 18;

impl FragLists {
    pub fn clear(&mut self) {
        self.frags.clear();
    }

    /// Releases the lists' memory beyond `KEEP_FRAGS` fragments (kept buffers stay bounded).
    pub fn trim(&mut self) {
        if self.frags.capacity() > KEEP_FRAGS || self.sorted.capacity() > KEEP_FRAGS {
            self.frags = Vec::new();
            self.sorted = Vec::new();
        }
    }

    /// Composites the fragments over `samples` (the opaque result, `n` samples). Fragments were
    /// pushed in submission order; a counting sort by sample keeps that order within a sample.
    pub fn composite(&mut self, samples: &mut [Sample], blend: Blend) {
        if self.frags.is_empty() {
            return;
        }
        let n = samples.len();
        self.start.clear();
        self.start.resize(n + 1, 0);
        for f in &self.frags {
            self.start[f.sample as usize + 1] += 1;
        }
        for i in 0..n {
            self.start[i + 1] += self.start[i];
        }
        self.sorted.clear();
        self.sorted.resize(self.frags.len(), Frag::default());
        self.next.clear();
        self.next.extend_from_slice(&self.start[..n]);
        for f in &self.frags {
            let slot = &mut self.next[f.sample as usize];
            self.sorted[*slot as usize] = *f;
            *slot += 1;
        }
        for (s, sample) in samples.iter_mut().enumerate() {
            let (lo, hi) = (self.start[s] as usize, self.start[s + 1] as usize);
            if lo == hi {
                continue;
            }
            let list = &mut self.sorted[lo..hi];
            if blend == Blend::Exact && list.len() > 1 {
                insertion_sort(list);
            }
            let mut c = sample.rgba;
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
    }
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
            let mut l = FragLists {
                frags,
                ..Default::default()
            };
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
    fn unsorted_blending_keeps_submission_order() {
        let frags = vec![frag(0, 0.9, 0.5, 1), frag(0, 0.2, 0.5, 2)];
        let mut l = FragLists {
            frags,
            ..Default::default()
        };
        let mut s = [Sample::BACKGROUND; 1];
        l.composite(&mut s, Blend::Unsorted);
        let want = over(
            [0.25, 0.125, 0.0, 0.5],
            over([0.25, 0.125, 0.0, 0.5], [0.0; 4]),
        );
        assert_eq!(s[0].rgba, want);
        assert_eq!(s[0].id, 1);
    }
}
