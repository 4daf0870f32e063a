//! Visibility over time at one sample, and the time integral of its colour.
//!
//! A sample holds fragments: the spans of shutter time during which one triangle covers it,
//! with the triangle's view depth at both ends (linear in between). The shutter is cut at every
//! fragment end, at every instant where two fragments present together (or a fragment and the
//! static background) cross in depth, and at the filter's kinks. On each resulting piece the
//! depth order is fixed: the layers are composited front to back (premultiplied *over*, stopping
//! at the first opaque one) at a few Gauss-Legendre points in time, and the piece adds
//! `(W(v) - W(u))` times the filter-weighted mean of those composites. Coverage is therefore
//! exact (up to the linear depth model) and colour is a quadrature of the shading over time.
//!
//! A fragment may stand for a run of triangles of one surface that cover the sample one after
//! the other (a chain, see `tiles.rs`); its layer is then shaded by the triangle of the chain
//! that covers the sample at each quadrature point.
use super::poly::ceil_i64;
use super::quadrature::{gauss, Quadrature};
use crate::shutter::Shutter;

/// Marks a fragment of a back-facing span (its normal is flipped for shading).
pub const BACK: u32 = 1 << 31;

/// One triangle's span of time at one sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frag {
    /// Shutter times of the span, `t0 < t1`.
    pub t0: f32,
    pub t1: f32,
    /// View depth at `t0` and `t1`.
    pub z0: f32,
    pub z1: f32,
    /// The tile's index of the (first) triangle, with `BACK` for back-facing spans.
    pub prim: u32,
    /// The first link of the fragment's chain of triangles, and how many it has.
    pub chain: u32,
    pub n: u32,
}

impl Frag {
    #[inline]
    fn depth(&self, t: f64) -> f64 {
        let (t0, t1) = (f64::from(self.t0), f64::from(self.t1));
        let (z0, z1) = (f64::from(self.z0), f64::from(self.z1));
        if t1 > t0 {
            z0 + (z1 - z0) * ((t - t0) / (t1 - t0)).clamp(0.0, 1.0)
        } else {
            z0
        }
    }
}

/// One triangle of a fragment's chain: it covers the sample from `t0` until the next link's
/// `t0` (the last one until the fragment's end).
#[derive(Clone, Copy, Debug)]
pub struct Link {
    pub t0: f32,
    /// The tile's index of the triangle.
    pub prim: u32,
    /// The next link, `NONE` at the end.
    pub next: u32,
}

/// No link, no fragment.
pub const NONE: u32 = u32::MAX;

/// The static scene behind the moving triangles at this sample: opaque colour and its depth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Backdrop {
    /// Premultiplied RGBA.
    pub rgba: [f32; 4],
    /// View depth, `inf` where nothing is there.
    pub depth: f32,
    /// Object id, -1 where nothing is there.
    pub id: i32,
}

/// Shading of the fragments' triangles at this sample.
pub trait Layers {
    /// True when the fragment's triangles are opaque everywhere (nothing behind shows).
    fn opaque(&self, f: &Frag) -> bool;
    /// The colour of fragment `f` when it is the same at every instant (its surface is of one
    /// colour), which [`Layers::shade`] would return up to rounding; None when it varies.
    fn uniform(&self, f: &Frag) -> Option<[f32; 4]>;
    /// Premultiplied RGBA of the surface of fragment `f` (index `i` of the sample's sorted
    /// fragments) seen at this sample at shutter time `t`. Calls for one fragment come in
    /// increasing `t`.
    fn shade(&mut self, i: usize, f: &Frag, t: f64) -> [f32; 4];
}

/// What one sample resolves to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resolved {
    /// Time-integrated premultiplied RGBA.
    pub rgba: [f32; 4],
    /// The front layer at the reference time: a fragment index and its depth then, or None
    /// when the backdrop (or nothing) is in front.
    pub front: Option<(usize, f64)>,
    /// Visible pieces shaded.
    pub pieces: u32,
}

/// Per-thread buffers of [`sweep`], kept across samples.
#[derive(Default)]
pub struct Scratch {
    active: Vec<usize>,
    cuts: Vec<f64>,
    order: Vec<(f64, usize)>,
    opaque: Vec<bool>,
}

/// A layer of a piece: a fragment index, or the backdrop.
pub const BACKDROP: usize = usize::MAX;

/// Sorts fragments by start time (then triangle: a unique key, so the order is the same
/// whatever order they were found in).
pub fn sort(frags: &mut [Frag]) {
    // start times are >= 0, so their bits order like the floats
    let key = |f: &Frag| (u64::from(f.t0.to_bits()) << 32) | u64::from(f.prim);
    if frags.len() > 16 {
        frags.sort_unstable_by_key(key);
        return;
    }
    // a sample holds a few fragments: insertion sort (the keys are unique, so any sort gives
    // this order)
    for i in 1..frags.len() {
        let f = frags[i];
        let k = key(&f);
        let mut j = i;
        while j > 0 && key(&frags[j - 1]) > k {
            frags[j] = frags[j - 1];
            j -= 1;
        }
        frags[j] = f;
    }
}

/// `W(b) - W(a)` ([`Shutter::cumulative`]), the box filter's inline.
#[inline(always)]
fn weight(shutter: &Shutter, a: f64, b: f64) -> f64 {
    match shutter {
        Shutter::Box => b.clamp(0.0, 1.0) - a.clamp(0.0, 1.0),
        s => s.cumulative(b) - s.cumulative(a),
    }
}

/// [`Shutter::density`], the box filter's inline.
#[inline(always)]
fn density(shutter: &Shutter, t: f64) -> f64 {
    match shutter {
        Shutter::Box => 1.0,
        s => s.density(t),
    }
}

/// Walks the shutter over the fragments of one sample (sorted by [`sort`]) in pieces of fixed
/// depth order:
/// `piece(a, b, layers)` gets each piece `[a, b]` with its layers front to back (fragment
/// indices, or `BACKDROP`), cut after the first opaque one. Pieces with no layer are skipped.
/// `breaks` are extra instants to cut at.
#[inline(always)]
pub fn sweep(
    frags: &[Frag],
    bg: &Backdrop,
    opaque: &[bool],
    breaks: &[f64],
    sc: &mut Scratch,
    mut piece: impl FnMut(f64, f64, &[(f64, usize)], &[Frag]),
) {
    let has_bg = bg.depth.is_finite();
    sc.active.clear();
    let (mut next, mut bi) = (0, 0);
    let mut u = 0.0f64;
    let depth_of = |i: usize, t: f64| {
        if i == BACKDROP {
            f64::from(bg.depth)
        } else {
            frags[i].depth(t)
        }
    };
    while u < 1.0 {
        while next < frags.len() && f64::from(frags[next].t0) <= u {
            sc.active.push(next);
            next += 1;
        }
        let mut kept = 0;
        for k in 0..sc.active.len() {
            let i = sc.active[k];
            if f64::from(frags[i].t1) > u {
                sc.active[kept] = i;
                kept += 1;
            }
        }
        sc.active.truncate(kept);
        let mut v = 1.0f64;
        if next < frags.len() {
            v = v.min(f64::from(frags[next].t0));
        }
        for &i in &sc.active {
            v = v.min(f64::from(frags[i].t1));
        }
        while bi < breaks.len() && breaks[bi] <= u {
            bi += 1;
        }
        if bi < breaks.len() {
            v = v.min(breaks[bi]);
        }
        let (a0, b0) = (u, v);
        u = v;
        let (u, v) = (a0, b0);
        if v <= u {
            continue;
        }
        let n = sc.active.len() + usize::from(has_bg);
        if n == 0 {
            continue;
        }
        // Cut where any two layers cross in depth.
        sc.cuts.clear();
        sc.cuts.push(u);
        if n > 1 {
            let layer = |a: usize| {
                if a < sc.active.len() {
                    sc.active[a]
                } else {
                    BACKDROP
                }
            };
            for a in 0..n {
                let ia = layer(a);
                for b in a + 1..n {
                    let ib = layer(b);
                    let g0 = depth_of(ia, u) - depth_of(ib, u);
                    let g1 = depth_of(ia, v) - depth_of(ib, v);
                    if (g0 < 0.0 && g1 > 0.0) || (g0 > 0.0 && g1 < 0.0) {
                        let x = u + (v - u) * (g0 / (g0 - g1));
                        if x > u && x < v {
                            sc.cuts.push(x);
                        }
                    }
                }
            }
        }
        sc.cuts.push(v);
        if sc.cuts.len() > 3 {
            sc.cuts[1..].sort_unstable_by(f64::total_cmp);
        }
        for c in 0..sc.cuts.len() - 1 {
            let (a, b) = (sc.cuts[c], sc.cuts[c + 1]);
            if b <= a {
                continue;
            }
            let mid = 0.5 * (a + b);
            sc.order.clear();
            for &i in &sc.active {
                sc.order.push((frags[i].depth(mid), i));
            }
            if has_bg {
                sc.order.push((f64::from(bg.depth), BACKDROP));
            }
            if sc.order.len() > 1 {
                sc.order
                    .sort_unstable_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
                if let Some(p) = sc
                    .order
                    .iter()
                    .position(|&(_, i)| i == BACKDROP || opaque[i])
                {
                    sc.order.truncate(p + 1);
                }
            }
            piece(a, b, &sc.order, frags);
        }
    }
}

/// Resolves the fragments of one sample (sorted here) over the backdrop `bg`: the shutter
/// integral of the composited colour, and the layer in front at `t_ref`. `breaks` are the
/// filter's interior breaks ([`Shutter::breaks`]).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn resolve(
    frags: &mut [Frag],
    bg: &Backdrop,
    layers: &mut impl Layers,
    shutter: &Shutter,
    breaks: &[f64],
    quad: Quadrature,
    t_ref: f64,
    sc: &mut Scratch,
) -> Resolved {
    let mut out = Resolved {
        rgba: [0.0; 4],
        front: None,
        pieces: 0,
    };
    let mut acc = [0.0f64; 4];
    let mut ref_done = false;
    sort(frags);
    let mut opaque = std::mem::take(&mut sc.opaque);
    opaque.clear();
    opaque.extend(frags.iter().map(|f| layers.opaque(f)));
    sweep(frags, bg, &opaque, breaks, sc, |a, b, order, frags| {
        if !ref_done && t_ref >= a && t_ref <= b {
            ref_done = true;
            out.front = match order.first() {
                Some(&(_, i)) if i != BACKDROP => Some((i, frags[i].depth(t_ref))),
                _ => None,
            };
        }
        let dw = weight(shutter, a, b);
        if dw <= 0.0 {
            return;
        }
        out.pieces += 1;
        if order.len() == 1 && order[0].1 == BACKDROP {
            for j in 0..4 {
                acc[j] += dw * f64::from(bg.rgba[j]);
            }
            return;
        }
        // Layers of one colour each: the composite is the same at every point in time, so its
        // filter-weighted mean over the piece is itself.
        if let Some(c) = composite_uniform(order, frags, bg, layers) {
            for j in 0..4 {
                acc[j] += dw * c[j];
            }
            return;
        }
        let elements = order
            .iter()
            .filter(|&&(_, i)| i != BACKDROP)
            .map(|&(_, i)| {
                let f = &frags[i];
                let share = (b - a) / (f64::from(f.t1) - f64::from(f.t0)).max(1e-30);
                ceil_i64(share * f64::from(f.n)).max(0) as usize
            })
            .max()
            .unwrap_or(1);
        let (xs, ws) = gauss(quad.points(b - a, elements));
        let (half, mid) = (0.5 * (b - a), 0.5 * (a + b));
        let mut sum = [0.0f64; 4];
        let mut wsum = 0.0;
        for (x, w) in xs.iter().zip(ws) {
            let t = mid + half * x;
            let wt = w * density(shutter, t);
            if wt <= 0.0 {
                continue;
            }
            let mut trans = 1.0f64;
            for &(_, i) in order {
                let s = if i == BACKDROP {
                    bg.rgba
                } else {
                    layers.shade(i, &frags[i], t)
                };
                for j in 0..4 {
                    sum[j] += wt * trans * f64::from(s[j]);
                }
                trans *= 1.0 - f64::from(s[3]);
                if trans <= 0.0 {
                    break;
                }
            }
            wsum += wt;
        }
        if wsum > 0.0 {
            for j in 0..4 {
                acc[j] += dw * sum[j] / wsum;
            }
        }
    });
    sc.opaque = opaque;
    out.rgba = acc.map(|x| x as f32);
    out
}

/// The composite of a piece's layers (front to back) when every layer is of one colour.
#[inline]
fn composite_uniform(
    order: &[(f64, usize)],
    frags: &[Frag],
    bg: &Backdrop,
    layers: &impl Layers,
) -> Option<[f64; 4]> {
    let mut sum = [0.0f64; 4];
    let mut trans = 1.0f64;
    for &(_, i) in order {
        let s = if i == BACKDROP {
            bg.rgba
        } else {
            layers.uniform(&frags[i])?
        };
        for j in 0..4 {
            sum[j] += trans * f64::from(s[j]);
        }
        trans *= 1.0 - f64::from(s[3]);
        if trans <= 0.0 {
            break;
        }
    }
    Some(sum)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Flat colours per prim; prims listed in `opaque` are opaque.
    struct Flat {
        colors: Vec<[f32; 4]>,
    }

    impl Layers for Flat {
        fn opaque(&self, f: &Frag) -> bool {
            self.colors[(f.prim & !BACK) as usize][3] >= 1.0
        }
        fn uniform(&self, _f: &Frag) -> Option<[f32; 4]> {
            None
        }
        fn shade(&mut self, _i: usize, f: &Frag, _t: f64) -> [f32; 4] {
            let c = self.colors[(f.prim & !BACK) as usize];
            [c[0] * c[3], c[1] * c[3], c[2] * c[3], c[3]]
        }
    }

    fn frag(t0: f32, t1: f32, z0: f32, z1: f32, prim: u32) -> Frag {
        Frag {
            t0,
            t1,
            z0,
            z1,
            prim,
            chain: 0,
            n: 1,
        }
    }

    const NONE: Backdrop = Backdrop {
        rgba: [0.0; 4],
        depth: f32::INFINITY,
        id: -1,
    };

    #[test]
    fn disjoint_spans_add_their_durations() {
        let mut l = Flat {
            colors: vec![[1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0]],
        };
        let mut f = vec![frag(0.5, 0.75, 2.0, 2.0, 1), frag(0.0, 0.25, 2.0, 2.0, 0)];
        let r = resolve(
            &mut f,
            &NONE,
            &mut l,
            &Shutter::Box,
            &[],
            Quadrature::Auto,
            0.1,
            &mut Scratch::default(),
        );
        assert_eq!(r.rgba, [0.25, 0.25, 0.0, 0.5]);
        assert_eq!(r.front.map(|x| f[x.0].prim), Some(0));
    }

    #[test]
    fn nearer_span_hides_farther_one_and_crossings_split() {
        let mut l = Flat {
            colors: vec![[1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0]],
        };
        // prim 0 from depth 1 to 3, prim 1 at depth 2 throughout: they cross at t = 0.5
        let mut f = vec![frag(0.0, 1.0, 1.0, 3.0, 0), frag(0.0, 1.0, 2.0, 2.0, 1)];
        let r = resolve(
            &mut f,
            &NONE,
            &mut l,
            &Shutter::Box,
            &[],
            Quadrature::Auto,
            1.0,
            &mut Scratch::default(),
        );
        assert_eq!(r.rgba, [0.5, 0.5, 0.0, 1.0]);
        assert_eq!(r.front.map(|x| f[x.0].prim), Some(1));
        // a ramp shutter weighs the later half 3x: W(1) - W(0.5) = 0.75
        let r = resolve(
            &mut f,
            &NONE,
            &mut l,
            &Shutter::Ramp,
            &[],
            Quadrature::Auto,
            1.0,
            &mut Scratch::default(),
        );
        assert!((r.rgba[0] - 0.25).abs() < 1e-7 && (r.rgba[1] - 0.75).abs() < 1e-7);
    }

    #[test]
    fn transparent_layers_composite_over_the_backdrop() {
        let mut l = Flat {
            colors: vec![[1.0, 0.0, 0.0, 0.5]],
        };
        let bg = Backdrop {
            rgba: [0.0, 0.0, 1.0, 1.0],
            depth: 5.0,
            id: 3,
        };
        let mut f = vec![frag(0.0, 0.5, 1.0, 1.0, 0)];
        let r = resolve(
            &mut f,
            &bg,
            &mut l,
            &Shutter::Box,
            &[],
            Quadrature::Auto,
            0.75,
            &mut Scratch::default(),
        );
        // first half: 0.5 red over blue, second half blue
        assert_eq!(r.rgba, [0.25, 0.0, 0.75, 1.0]);
        assert_eq!(r.front, None);
        // a span behind the backdrop shows nothing
        let mut f = vec![frag(0.0, 1.0, 9.0, 9.0, 0)];
        let r = resolve(
            &mut f,
            &bg,
            &mut l,
            &Shutter::Box,
            &[],
            Quadrature::Auto,
            0.5,
            &mut Scratch::default(),
        );
        assert_eq!(r.rgba, [0.0, 0.0, 1.0, 1.0]);
    }
}
