//! The time integral of one sample's colour.
//!
//! [`resolve`] takes the pieces of fixed depth order that [`sweep`] finds, composites their
//! layers front to back (premultiplied *over*, stopping at the first opaque one) at a few
//! Gauss-Legendre points in time, and adds `(W(v) - W(u))` times the filter-weighted mean of
//! those composites. Pieces that touch and hold the same layers in the same order (the sweep
//! cut between them at an event behind the visible layers: a hidden chain's link, a hidden
//! fragment's end, a crossing of hidden layers) are integrated as one: what shows does not
//! change there, so a dense mesh behind a surface adds no shading work. Coverage is therefore exact (up to the depth model, linear per triangle)
//! and colour is a quadrature of the shading over time. A piece is cut where a layer's chain
//! passes from one triangle to the next, so each sub-piece is shaded by one triangle per
//! layer at its own Gauss points, and where a light grazes a lambert layer (the kink of its
//! `max(0, n . l)`, which the Gauss points would integrate as if smooth); layers of one colour
//! skip the quadrature.
use super::quadrature::{gauss, Quadrature};
use super::visibility::{
    depth_at, sort, sort_times, sweep, Frag, Link, Overflow, StaticSample, Sweep, BACKDROP, NONE,
};
use crate::shutter::Shutter;

/// Shading of the fragments' triangles at this sample.
pub trait Layers {
    /// True when the fragment's triangles are opaque everywhere (nothing behind shows).
    fn opaque(&self, f: &Frag) -> bool;
    /// The colour of fragment `f` when it is the same at every instant (its surface is of one
    /// colour), which [`Layers::shade`] would return up to rounding; None when it varies.
    fn uniform(&self, f: &Frag) -> Option<[f32; 4]>;
    /// The triangle of fragment `f` (index `i` of the sample's sorted fragments) covering the
    /// sample at shutter time `t`, with `f`'s `BACK` flag, and the time from which the next
    /// triangle of its chain covers it (infinity for the last). Calls for one fragment come in
    /// increasing `t`.
    fn triangle(&mut self, i: usize, f: &Frag, t: f64) -> (u32, f64);
    /// How much the shading of triangle `p` varies across it ([`Quadrature::points`]).
    fn bend(&self, p: u32) -> f32;
    /// Premultiplied RGBA of triangle `p` (as [`Layers::triangle`] gives it) seen at this
    /// sample at shutter time `t`.
    fn shade(&mut self, p: u32, t: f64) -> [f32; 4];
    /// Pushes the instants strictly inside `(a, b)` where fragment `f`'s chain passes from one
    /// triangle to the next, ascending.
    fn cuts(&mut self, i: usize, f: &Frag, a: f64, b: f64, out: &mut Vec<f64>);
    /// Pushes the instants strictly inside `(a, b)` where the shading of triangle `p` (as
    /// [`Layers::triangle`] gives it) at this sample has a kink: where a light grazes a lambert
    /// surface (its `max(0, n . l)` turns on or off), ascending per light.
    fn kinks(&mut self, p: u32, a: f64, b: f64, out: &mut Vec<f64>);
}

/// What one sample resolves to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resolved {
    /// Time-integrated premultiplied RGBA.
    pub rgba: [f32; 4],
    /// The front layer at the reference time: a fragment index and its depth then, or None
    /// when the backdrop (or nothing) is in front.
    pub front: Option<(usize, f64)>,
    /// Stretches of time shaded: of fixed layers and triangles (one quadrature each), or of
    /// one uniform composite.
    pub pieces: u32,
}

/// Per-thread buffers of [`resolve`], kept across samples, and their limit.
#[derive(Default)]
pub struct Scratch {
    /// [`sweep`]'s buffers and its limit (most depth crossings one stretch of a sample's time
    /// may hold; unlimited by default).
    pub sweep: Sweep,
    opaque: Vec<bool>,
    element_cuts: Vec<f64>,
    kinks: Vec<f64>,
    tris: Vec<(u32, f64)>,
    merged: Vec<(f64, usize)>,
    /// Whether pieces of the same layers that touch are integrated as one (the default; off
    /// only to test that joining them changes nothing but rounding).
    pub split: bool,
    /// Whether [`resolve`] notes which layer is in front when ([`Scratch::seen`]).
    pub exposure: bool,
    /// With `exposure`, the sample's layers that were in front, after [`resolve`].
    pub seen: Vec<Seen>,
}

/// No layer at all: neither a fragment nor the backdrop is there.
pub const NOTHING: usize = usize::MAX - 1;

/// A layer in front at one sample over part of the shutter: the frontmost one (whatever its
/// alpha), the backdrop where no fragment is in front of it, or [`NOTHING`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Seen {
    /// A fragment index (of the sorted fragments), `BACKDROP` or [`NOTHING`].
    pub layer: usize,
    /// The filter's weight of the time it is in front (`W(b) - W(a)` summed over its pieces).
    pub weight: f64,
    /// The first and last instant it is in front (over pieces of positive length, whatever
    /// their weight).
    pub first: f64,
    pub last: f64,
}

/// Adds the piece `[a, b]` of weight `dw` to `layer`'s entry in `seen`.
fn note(seen: &mut Vec<Seen>, layer: usize, a: f64, b: f64, dw: f64) {
    match seen.iter_mut().find(|s| s.layer == layer) {
        Some(s) => {
            s.weight += dw;
            s.first = s.first.min(a);
            s.last = s.last.max(b);
        }
        None => seen.push(Seen {
            layer,
            weight: dw,
            first: a,
            last: b,
        }),
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

/// The shutter one sample is resolved over: the filter, its interior breaks
/// ([`Shutter::breaks`]), the points in time per visible piece and the reference time (the
/// instant whose front layer the sample reports).
///
/// `window`: a rolling shutter's row exposure `(o, s)`, or None (a global shutter, the whole of
/// [0, 1]). The sample is then exposed over `[o, o + s]` only, the filter rescaled to it:
/// `W_row(t) = W((t - o) / s)` and `w_row(t) = w((t - o) / s) / s` inside it, 0 outside.
/// `breaks` must then hold the window's ends (those inside (0, 1)) and the filter's breaks
/// mapped into it, and `t_ref` the reference instant mapped into it (`o + s t_ref`).
#[derive(Clone, Copy)]
pub struct Timing<'a> {
    pub shutter: &'a Shutter,
    pub breaks: &'a [f64],
    pub quad: Quadrature,
    pub t_ref: f64,
    pub window: Option<(f64, f64)>,
}

impl Timing<'_> {
    /// The filter's weight of `[a, b]` (in the row's window, if any).
    #[inline(always)]
    fn weight(&self, a: f64, b: f64) -> f64 {
        match self.window {
            None => weight(self.shutter, a, b),
            Some((o, s)) => weight(self.shutter, (a - o) / s, (b - o) / s),
        }
    }

    /// The filter's density at `t` (in the row's window, if any: 0 outside it).
    #[inline(always)]
    fn density(&self, t: f64) -> f64 {
        match self.window {
            None => density(self.shutter, t),
            Some((o, s)) => {
                let u = (t - o) / s;
                if (0.0..=1.0).contains(&u) {
                    density(self.shutter, u) / s
                } else {
                    0.0
                }
            }
        }
    }
}

/// The time integral of one sample's colour as the pieces come (see the module doc), with the
/// buffers it reuses.
struct Integral<'s, L> {
    layers: &'s mut L,
    bg: &'s StaticSample,
    time: Timing<'s>,
    /// The sum so far, `W(v) - W(u)` times each piece's mean composite.
    acc: [f64; 4],
    /// Where the piece's chains pass from one triangle to the next.
    cuts: Vec<f64>,
    /// Where a sub-piece's shading has a kink.
    kinks: Vec<f64>,
    /// Each layer's triangle of the sub-piece, and the time its chain's next one starts.
    tris: Vec<(u32, f64)>,
    /// Stretches of time shaded so far (one composite or one quadrature each).
    shaded: u32,
}

impl<L: Layers> Integral<'_, L> {
    /// Adds the piece `[a, b]` of filter weight `dw` with its layers `order` (front to back).
    #[inline(always)]
    fn piece(&mut self, a: f64, b: f64, dw: f64, order: &[(f64, usize)], frags: &[Frag]) {
        if order.len() == 1 && order[0].1 == BACKDROP {
            self.shaded += 1;
            for j in 0..4 {
                self.acc[j] += dw * f64::from(self.bg.rgba[j]);
            }
            return;
        }
        // Layers of one colour each: the composite is the same at every point in time, so its
        // filter-weighted mean over the piece is itself (whichever triangle of a chain covers
        // the sample).
        if let Some(c) = composite_uniform(order, frags, self.bg, self.layers) {
            self.shaded += 1;
            for j in 0..4 {
                self.acc[j] += dw * c[j];
            }
            return;
        }
        // Cut where a layer's chain passes from one triangle to the next: every sub-piece is
        // shaded by the same triangles throughout.
        let mut cuts = std::mem::take(&mut self.cuts);
        cuts.clear();
        cuts.push(a);
        let mut chained = 0;
        for &(_, i) in order {
            if i != BACKDROP && frags[i].n > 1 {
                let before = cuts.len();
                self.layers.cuts(i, &frags[i], a, b, &mut cuts);
                chained += usize::from(cuts.len() > before);
            }
        }
        cuts.push(b);
        // each layer's cuts come ascending; several layers' cuts interleave
        if chained > 1 {
            let n = cuts.len();
            sort_times(&mut cuts[1..n - 1]);
        }
        for c in 0..cuts.len() - 1 {
            let (u, v) = (cuts[c], cuts[c + 1]);
            if v <= u {
                continue;
            }
            let dw = if cuts.len() == 2 {
                dw
            } else {
                self.time.weight(u, v)
            };
            if dw > 0.0 {
                self.sub_piece(u, v, dw, order, frags);
            }
        }
        self.cuts = cuts;
    }

    /// Adds the sub-piece `[u, v]` (of weight `dw`), shaded by one triangle per layer, cut
    /// where a light grazes one of them.
    #[inline(always)]
    fn sub_piece(&mut self, u: f64, v: f64, dw: f64, order: &[(f64, usize)], frags: &[Frag]) {
        self.shaded += 1;
        // each layer's triangle, found at the first point in time and kept while the points
        // stay before its chain's next link
        let quad = self.time.quad;
        let mid = 0.5 * (u + v);
        let (xs, _) = gauss(quad.points(v - u, 0.0));
        let first = mid + 0.5 * (v - u) * xs[0];
        let mut bend = 0.0f32;
        self.tris.clear();
        self.kinks.clear();
        for &(_, i) in order {
            if i == BACKDROP {
                self.tris.push((NONE, f64::INFINITY));
            } else {
                let tri = self.layers.triangle(i, &frags[i], first);
                bend = bend.max(self.layers.bend(tri.0));
                self.layers.kinks(tri.0, u, v, &mut self.kinks);
                self.tris.push(tri);
            }
        }
        // Lambert's clamp bends the shading where a light grazes a surface: the quadrature is
        // exact only for smooth shading, so the piece is cut there too.
        if self.kinks.len() > 1 {
            sort_times(&mut self.kinks);
        }
        let mut lo = u;
        for k in 0..=self.kinks.len() {
            let hi = if k < self.kinks.len() {
                self.kinks[k]
            } else {
                v
            };
            if hi <= lo {
                continue;
            }
            let dw = if self.kinks.is_empty() {
                dw
            } else {
                self.time.weight(lo, hi)
            };
            let (a, b) = (lo, hi);
            lo = hi;
            if dw > 0.0 {
                self.quadrature((a, b), dw, bend, order, frags);
            }
        }
    }

    /// Adds `dw` times the filter-weighted mean of the composites at the Gauss points of
    /// `[a, b]` (a smooth stretch whose shading bends by `bend`).
    #[inline(always)]
    fn quadrature(
        &mut self,
        (a, b): (f64, f64),
        dw: f64,
        bend: f32,
        order: &[(f64, usize)],
        frags: &[Frag],
    ) {
        let (half, mid) = (0.5 * (b - a), 0.5 * (a + b));
        let (xs, ws) = gauss(self.time.quad.points(b - a, bend));
        let mut sum = [0.0f64; 4];
        let mut wsum = 0.0;
        for (x, w) in xs.iter().zip(ws) {
            let t = mid + half * x;
            let wt = w * self.time.density(t);
            if wt <= 0.0 {
                continue;
            }
            let mut trans = 1.0f64;
            for (k, &(_, i)) in order.iter().enumerate() {
                let s = if i == BACKDROP {
                    self.bg.rgba
                } else {
                    if t >= self.tris[k].1 {
                        self.tris[k] = self.layers.triangle(i, &frags[i], t);
                    }
                    self.layers.shade(self.tris[k].0, t)
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
            if power_of_two(wsum) {
                // dividing by a power of two is multiplying by its exact reciprocal
                let inv = 1.0 / wsum;
                for j in 0..4 {
                    self.acc[j] += dw * sum[j] * inv;
                }
            } else {
                for j in 0..4 {
                    self.acc[j] += dw * sum[j] / wsum;
                }
            }
        }
    }
}

/// Resolves the fragments of one sample (sorted here) over the backdrop `bg`: the integral
/// over the shutter `time` of the composited colour, and the layer in front at its reference
/// time. With `sc.exposure`, `sc.seen` then holds every layer that was in front (the first of
/// a piece's, whatever its alpha; [`NOTHING`] where no layer is there) with the filter's weight
/// of those times and their first and last instant. Fails where [`sweep`] does (more depth
/// crossings than `sc.sweep.max_cuts`).
#[inline(always)]
pub fn resolve(
    frags: &mut [Frag],
    links: &[Link],
    bg: &StaticSample,
    layers: &mut impl Layers,
    time: Timing,
    sc: &mut Scratch,
) -> Result<Resolved, Overflow> {
    let mut out = Resolved {
        rgba: [0.0; 4],
        front: None,
        pieces: 0,
    };
    let mut ref_done = false;
    let t_ref = time.t_ref;
    let mut integral = Integral {
        layers,
        bg,
        time,
        acc: [0.0; 4],
        cuts: std::mem::take(&mut sc.element_cuts),
        kinks: std::mem::take(&mut sc.kinks),
        tris: std::mem::take(&mut sc.tris),
        shaded: 0,
    };
    sort(frags);
    let exposure = sc.exposure;
    let mut seen = std::mem::take(&mut sc.seen);
    seen.clear();
    // the end of the last piece so far: the time before the next one has no layer
    let mut covered = 0.0f64;
    // the piece waiting to be integrated: `[a, b]`, and whether there is one (1) or not (0);
    // its layers front to back in `merged`
    let mut pending = (0.0f64, 0.0f64, 0u8);
    let split = sc.split;
    // pieces of the same layers join below (unless split), and nothing is noted per piece
    // unless for the exposure: the sweep may give such pieces joined
    sc.sweep.joined = !split && !exposure;
    let mut merged = std::mem::take(&mut sc.merged);
    merged.clear();
    let mut opaque = std::mem::take(&mut sc.opaque);
    opaque.clear();
    opaque.extend(frags.iter().map(|f| integral.layers.opaque(f)));
    let swept = sweep(
        frags,
        links,
        bg,
        &opaque,
        time.breaks,
        &mut sc.sweep,
        |a, b, order, frags| {
            if !ref_done && t_ref >= a && t_ref <= b {
                ref_done = true;
                out.front = match order.first() {
                    Some(&(_, i)) if i != BACKDROP => Some((i, depth_at(&frags[i], links, t_ref))),
                    _ => None,
                };
            }
            if exposure {
                let dw = time.weight(a, b);
                if a > covered {
                    note(&mut seen, NOTHING, covered, a, time.weight(covered, a));
                }
                note(&mut seen, order.first().map_or(NOTHING, |o| o.1), a, b, dw);
                covered = b;
            }
            // A piece that continues the pending one with the same layers in the same order
            // (the sweep cut between them at an event behind them: a hidden chain's link or
            // end, a crossing of hidden layers) joins it, unless a filter break lies between.
            if pending.2 > 0
                && pending.1 == a
                && !split
                && same_layers(&merged, order)
                && !time.breaks.contains(&a)
            {
                pending.1 = b;
                return;
            }
            flush(&mut integral, &pending, &merged, frags);
            merged.clear();
            merged.extend_from_slice(order);
            pending = (a, b, 1);
        },
    );
    flush(&mut integral, &pending, &merged, frags);
    sc.merged = merged;
    if exposure && covered < 1.0 {
        note(&mut seen, NOTHING, covered, 1.0, time.weight(covered, 1.0));
    }
    sc.seen = seen;
    sc.opaque = opaque;
    sc.element_cuts = integral.cuts;
    sc.kinks = integral.kinks;
    sc.tris = integral.tris;
    swept?;
    out.rgba = integral.acc.map(|x| x as f32);
    out.pieces = integral.shaded;
    Ok(out)
}

/// Whether `order` holds the same layers as `merged`, in the same order (their depths aside).
#[inline(always)]
fn same_layers(merged: &[(f64, usize)], order: &[(f64, usize)]) -> bool {
    merged.len() == order.len() && merged.iter().zip(order).all(|(m, o)| m.1 == o.1)
}

/// Integrates the pending piece `[a, b]` (if any) with its layers `order`.
#[inline(always)]
fn flush<L: Layers>(
    integral: &mut Integral<'_, L>,
    &(a, b, some): &(f64, f64, u8),
    order: &[(f64, usize)],
    frags: &[Frag],
) {
    if some == 0 {
        return;
    }
    let dw = integral.time.weight(a, b);
    if dw <= 0.0 {
        return;
    }
    integral.piece(a, b, dw, order, frags);
}

/// True when `x` is a normal power of two (its reciprocal is exact, so multiplying by it gives
/// the same bits as dividing by `x`). The weights of Gauss rules of 1 and 2 points sum to 2.
#[inline(always)]
fn power_of_two(x: f64) -> bool {
    const MANTISSA: u64 = (1 << 52) - 1;
    x.is_normal() && x.to_bits() & MANTISSA == 0 && x < 2f64.powi(1000)
}

/// The composite of a piece's layers (front to back) when every layer is of one colour.
#[inline]
fn composite_uniform(
    order: &[(f64, usize)],
    frags: &[Frag],
    bg: &StaticSample,
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
    use super::super::visibility::BACK;
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
        fn cuts(&mut self, _i: usize, _f: &Frag, _a: f64, _b: f64, _out: &mut Vec<f64>) {}
        fn kinks(&mut self, _p: u32, _a: f64, _b: f64, _out: &mut Vec<f64>) {}
        fn triangle(&mut self, _i: usize, f: &Frag, _t: f64) -> (u32, f64) {
            (f.prim, f64::INFINITY)
        }
        fn bend(&self, _p: u32) -> f32 {
            0.0
        }
        fn shade(&mut self, p: u32, _t: f64) -> [f32; 4] {
            let c = self.colors[(p & !BACK) as usize];
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

    const LINK: [Link; 1] = [Link {
        t0: 0.0,
        z0: 0.0,
        prim: 0,
        next: NONE,
    }];

    const EMPTY: StaticSample = StaticSample {
        rgba: [0.0; 4],
        depth: f32::INFINITY,
        id: -1,
    };

    #[test]
    fn powers_of_two_are_told_apart() {
        assert!(power_of_two(2.0) && power_of_two(1.0) && power_of_two(0.25));
        assert!(!power_of_two(3.0) && !power_of_two(0.0) && !power_of_two(f64::INFINITY));
        assert!(!power_of_two(f64::MIN_POSITIVE / 2.0) && !power_of_two(f64::NAN));
        // the 1- and 2-point rules' weights sum to 2; a divide by it is the multiply
        for x in [0.3f64, 1e-30, 0.123_456_789] {
            assert_eq!(0.7 * x / 2.0, 0.7 * x * 0.5);
        }
    }

    #[test]
    fn disjoint_spans_add_their_durations() {
        let mut l = Flat {
            colors: vec![[1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0]],
        };
        let mut f = vec![frag(0.5, 0.75, 2.0, 2.0, 1), frag(0.0, 0.25, 2.0, 2.0, 0)];
        let r = resolve(
            &mut f,
            &LINK,
            &EMPTY,
            &mut l,
            Timing {
                shutter: &Shutter::Box,
                breaks: &[],
                quad: Quadrature::Auto,
                t_ref: 0.1,
                window: None,
            },
            &mut Scratch::default(),
        )
        .unwrap();
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
            &LINK,
            &EMPTY,
            &mut l,
            Timing {
                shutter: &Shutter::Box,
                breaks: &[],
                quad: Quadrature::Auto,
                t_ref: 1.0,
                window: None,
            },
            &mut Scratch::default(),
        )
        .unwrap();
        assert_eq!(r.rgba, [0.5, 0.5, 0.0, 1.0]);
        assert_eq!(r.front.map(|x| f[x.0].prim), Some(1));
        // a ramp shutter weighs the later half 3x: W(1) - W(0.5) = 0.75
        let r = resolve(
            &mut f,
            &LINK,
            &EMPTY,
            &mut l,
            Timing {
                shutter: &Shutter::Ramp,
                breaks: &[],
                quad: Quadrature::Auto,
                t_ref: 1.0,
                window: None,
            },
            &mut Scratch::default(),
        )
        .unwrap();
        assert!((r.rgba[0] - 0.25).abs() < 1e-7 && (r.rgba[1] - 0.75).abs() < 1e-7);
    }

    #[test]
    fn a_rolling_window_weighs_only_its_own_time_rescaled() {
        let mut l = Flat {
            colors: vec![[1.0, 0.0, 0.0, 1.0]],
        };
        // red over [0, 0.5]; the row's window [0.25, 0.75] sees it half of its time
        let mut f = vec![frag(0.0, 0.5, 1.0, 1.0, 0)];
        let time = |shutter, breaks| Timing {
            shutter,
            breaks,
            quad: Quadrature::Auto,
            t_ref: 0.5,
            window: Some((0.25, 0.5)),
        };
        let r = resolve(
            &mut f,
            &LINK,
            &EMPTY,
            &mut l,
            time(&Shutter::Box, &[0.25, 0.75]),
            &mut Scratch::default(),
        )
        .unwrap();
        assert_eq!(r.rgba, [0.5, 0.0, 0.0, 0.5]);
        // a ramp over the window weighs its first half W(0.5) = 0.25
        let r = resolve(
            &mut f,
            &LINK,
            &EMPTY,
            &mut l,
            time(&Shutter::Ramp, &[0.25, 0.75]),
            &mut Scratch::default(),
        )
        .unwrap();
        assert!((r.rgba[0] - 0.25).abs() < 1e-7 && (r.rgba[3] - 0.25).abs() < 1e-7);
        assert_eq!(r.front.map(|x| f[x.0].prim), Some(0));
    }

    #[test]
    fn rows_windows_follow_the_readout_and_its_direction() {
        use super::super::input::Rolling;
        assert_eq!(Rolling::default().window(5, 10), None);
        let down = Rolling {
            readout: 0.5,
            bottom_to_top: false,
        };
        assert_eq!(down.window(0, 10), Some((0.0, 0.5)));
        assert_eq!(down.window(9, 10), Some((0.45, 0.5)));
        let up = Rolling {
            bottom_to_top: true,
            ..down
        };
        assert_eq!(up.window(9, 10), Some((0.0, 0.5)));
        assert_eq!(up.window(0, 10), Some((0.45, 0.5)));
    }

    #[test]
    fn transparent_layers_composite_over_the_backdrop() {
        let mut l = Flat {
            colors: vec![[1.0, 0.0, 0.0, 0.5]],
        };
        let bg = StaticSample {
            rgba: [0.0, 0.0, 1.0, 1.0],
            depth: 5.0,
            id: 3,
        };
        let mut f = vec![frag(0.0, 0.5, 1.0, 1.0, 0)];
        let r = resolve(
            &mut f,
            &LINK,
            &bg,
            &mut l,
            Timing {
                shutter: &Shutter::Box,
                breaks: &[],
                quad: Quadrature::Auto,
                t_ref: 0.75,
                window: None,
            },
            &mut Scratch::default(),
        )
        .unwrap();
        // first half: 0.5 red over blue, second half blue
        assert_eq!(r.rgba, [0.25, 0.0, 0.75, 1.0]);
        assert_eq!(r.front, None);
        // a span behind the backdrop shows nothing
        let mut f = vec![frag(0.0, 1.0, 9.0, 9.0, 0)];
        let r = resolve(
            &mut f,
            &LINK,
            &bg,
            &mut l,
            Timing {
                shutter: &Shutter::Box,
                breaks: &[],
                quad: Quadrature::Auto,
                t_ref: 0.5,
                window: None,
            },
            &mut Scratch::default(),
        )
        .unwrap();
        assert_eq!(r.rgba, [0.0, 0.0, 1.0, 1.0]);
    }

    /// Colours that change linearly in time (the midpoint rule integrates them exactly, so
    /// pieces joined or not give the same integral up to rounding).
    struct Ramp {
        colors: Vec<[f32; 4]>,
    }

    impl Layers for Ramp {
        fn opaque(&self, f: &Frag) -> bool {
            self.colors[(f.prim & !BACK) as usize][3] >= 1.0
        }
        fn uniform(&self, _f: &Frag) -> Option<[f32; 4]> {
            None
        }
        fn cuts(&mut self, _i: usize, _f: &Frag, _a: f64, _b: f64, _out: &mut Vec<f64>) {}
        fn kinks(&mut self, _p: u32, _a: f64, _b: f64, _out: &mut Vec<f64>) {}
        fn triangle(&mut self, _i: usize, f: &Frag, _t: f64) -> (u32, f64) {
            (f.prim, f64::INFINITY)
        }
        fn bend(&self, _p: u32) -> f32 {
            0.0
        }
        fn shade(&mut self, p: u32, t: f64) -> [f32; 4] {
            let c = self.colors[(p & !BACK) as usize];
            let k = (0.25 + 0.5 * t) as f32;
            [c[0] * c[3] * k, c[1] * c[3] * k, c[2] * c[3], c[3]]
        }
    }

    /// A small deterministic generator (xorshift), uniform in [0, 1).
    fn uniform(state: &mut u64) -> f32 {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        (*state >> 40) as f32 / (1u64 << 24) as f32
    }

    #[test]
    fn joining_pieces_of_the_same_layers_changes_nothing_but_rounding() {
        // Random samples of up to 8 fragments, most opaque, crossing in depth, over a backdrop:
        // events behind the front layer (hidden ends and crossings) cut the sweep, and the
        // pieces on either side of them with the same layers are integrated as one.
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let (mut joined, mut split) = (0u64, 0u64);
        for case in 0..400 {
            let n = 1 + (uniform(&mut state) * 8.0) as usize;
            let mut frags = Vec::new();
            let mut colors = Vec::new();
            for k in 0..n {
                let (a, b) = (uniform(&mut state), uniform(&mut state));
                let (t0, t1) = (a.min(b), a.max(b).max(a.min(b) + 1e-3));
                let z = [
                    1.0 + 4.0 * uniform(&mut state),
                    1.0 + 4.0 * uniform(&mut state),
                ];
                frags.push(frag(t0, t1.min(1.0), z[0], z[1], k as u32));
                let alpha = if uniform(&mut state) < 0.8 { 1.0 } else { 0.5 };
                colors.push([uniform(&mut state), uniform(&mut state), 0.5, alpha]);
            }
            let bg = StaticSample {
                rgba: [0.1, 0.2, 0.3, 1.0],
                depth: if case % 2 == 0 { 4.0 } else { f32::INFINITY },
                id: 1,
            };
            let run = |split_pieces: bool| {
                let mut f = frags.clone();
                let mut sc = Scratch {
                    split: split_pieces,
                    ..Scratch::default()
                };
                let time = Timing {
                    shutter: &Shutter::Box,
                    breaks: &[],
                    quad: Quadrature::Auto,
                    t_ref: 0.5,
                    window: None,
                };
                let mut l = Ramp {
                    colors: colors.clone(),
                };
                let r = resolve(&mut f, &LINK, &bg, &mut l, time, &mut sc).unwrap();
                (r, f)
            };
            let ((a, fa), (b, fb)) = (run(false), run(true));
            for j in 0..4 {
                assert!(
                    (a.rgba[j] - b.rgba[j]).abs() < 1e-6,
                    "case {case}: {a:?} {b:?}"
                );
            }
            assert_eq!(a.front.map(|x| fa[x.0].prim), b.front.map(|x| fb[x.0].prim));
            assert!(a.pieces <= b.pieces);
            if n == 1 && !bg.depth.is_finite() {
                assert_eq!(
                    a, b,
                    "one fragment alone: no event behind it, the same bits"
                );
            }
            joined += u64::from(a.pieces);
            split += u64::from(b.pieces);
        }
        assert!(joined < split, "{joined} pieces joined, {split} split");
    }
}
