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

/// One triangle of a fragment's chain: it covers the sample from `t0` until the next link's
/// `t0` (the last one until the fragment's end).
#[derive(Clone, Copy, Debug)]
pub struct Link {
    pub t0: f32,
    /// The view depth at `t0` (the triangle's depth is linear until the next link).
    pub z0: f32,
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
    /// Pushes the instants strictly inside `(a, b)` where fragment `f`'s chain passes from one
    /// triangle to the next, ascending.
    fn cuts(&mut self, i: usize, f: &Frag, a: f64, b: f64, out: &mut Vec<f64>);
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
    sub: Vec<f64>,
    lines: Vec<(usize, [f64; 4])>,
    cursor: Vec<u32>,
    opaque: Vec<bool>,
    element_cuts: Vec<f64>,
}

/// A layer of a piece: a fragment index, or the backdrop.
pub const BACKDROP: usize = usize::MAX;

/// The straight piece of fragment `i`'s depth around time `t`: `[t_a, z_a, t_b, z_b]`, from the
/// link of its chain covering `t` (found from `cursor[i]`, moved forward) to the next.
fn element_line(frags: &[Frag], links: &[Link], cursor: &mut [u32], i: usize, t: f64) -> [f64; 4] {
    let f = &frags[i];
    let mut c = cursor[i];
    loop {
        let next = links[c as usize].next;
        if next == NONE || f64::from(links[next as usize].t0) > t {
            break;
        }
        c = next;
    }
    cursor[i] = c;
    let l = &links[c as usize];
    let next = l.next;
    let (tb, zb) = if next == NONE {
        (f.t1, f.z1)
    } else {
        (links[next as usize].t0, links[next as usize].z0)
    };
    let ta = if c == f.chain { f.t0 } else { l.t0 };
    let za = if c == f.chain { f.z0 } else { l.z0 };
    [f64::from(ta), f64::from(za), f64::from(tb), f64::from(zb)]
}

/// The view depth of fragment `f`'s surface at time `t` (from its chain's link then).
pub fn depth_at(f: &Frag, links: &[Link], t: f64) -> f64 {
    let mut cur = [f.chain];
    let l = element_line(std::slice::from_ref(f), links, &mut cur, 0, t);
    if l[2] > l[0] {
        l[1] + (l[3] - l[1]) * ((t - l[0]) / (l[2] - l[0])).clamp(0.0, 1.0)
    } else {
        l[1]
    }
}

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
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn sweep(
    frags: &[Frag],
    links: &[Link],
    bg: &Backdrop,
    opaque: &[bool],
    breaks: &[f64],
    sc: &mut Scratch,
    mut piece: impl FnMut(f64, f64, &[(f64, usize)], &[Frag]),
) {
    let has_bg = bg.depth.is_finite();
    sc.active.clear();
    sc.cursor.clear();
    sc.cursor.extend(frags.iter().map(|f| f.chain));
    let (mut next, mut bi) = (0, 0);
    let mut u = 0.0f64;
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
        if n == 1 {
            // one layer: no depth to compare
            sc.order.clear();
            sc.order
                .push((0.0, sc.active.first().copied().unwrap_or(BACKDROP)));
            piece(u, v, &sc.order, frags);
            continue;
        }
        // Chains change triangle (and depth slope) at their links: cut there first, so that
        // every layer's depth is one straight piece on each sub-interval.
        sc.sub.clear();
        sc.sub.push(u);
        for &i in &sc.active {
            if frags[i].n > 1 {
                let mut c = frags[i].chain;
                while let Some(next) = Some(links[c as usize].next).filter(|&x| x != NONE) {
                    let t = f64::from(links[next as usize].t0);
                    if t >= v {
                        break;
                    }
                    if t > u {
                        sc.sub.push(t);
                    }
                    c = next;
                }
            }
        }
        sc.sub.push(v);
        if sc.sub.len() > 3 {
            sc.sub[1..].sort_unstable_by(f64::total_cmp);
        }
        for k in 0..sc.sub.len() - 1 {
            let (p, q) = (sc.sub[k], sc.sub[k + 1]);
            if q <= p {
                continue;
            }
            let mid = 0.5 * (p + q);
            // each layer's straight depth on [p, q]
            sc.lines.clear();
            for &i in &sc.active {
                sc.lines
                    .push((i, element_line(frags, links, &mut sc.cursor, i, mid)));
            }
            if has_bg {
                let z = f64::from(bg.depth);
                sc.lines.push((BACKDROP, [0.0, z, 1.0, z]));
            }
            let at = |l: &[f64; 4], t: f64| {
                if l[2] > l[0] {
                    l[1] + (l[3] - l[1]) * ((t - l[0]) / (l[2] - l[0])).clamp(0.0, 1.0)
                } else {
                    l[1]
                }
            };
            // cut where any two layers cross in depth
            sc.cuts.clear();
            sc.cuts.push(p);
            for a in 0..sc.lines.len() {
                for b in a + 1..sc.lines.len() {
                    let (la, lb) = (&sc.lines[a].1, &sc.lines[b].1);
                    let g0 = at(la, p) - at(lb, p);
                    let g1 = at(la, q) - at(lb, q);
                    if (g0 < 0.0 && g1 > 0.0) || (g0 > 0.0 && g1 < 0.0) {
                        let x = p + (q - p) * (g0 / (g0 - g1));
                        if x > p && x < q {
                            sc.cuts.push(x);
                        }
                    }
                }
            }
            sc.cuts.push(q);
            if sc.cuts.len() > 3 {
                sc.cuts[1..].sort_unstable_by(f64::total_cmp);
            }
            for c in 0..sc.cuts.len() - 1 {
                let (a, b) = (sc.cuts[c], sc.cuts[c + 1]);
                if b <= a {
                    continue;
                }
                let m = 0.5 * (a + b);
                sc.order.clear();
                for (i, l) in &sc.lines {
                    sc.order.push((at(l, m), *i));
                }
                sc.order
                    .sort_unstable_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
                if let Some(p) = sc
                    .order
                    .iter()
                    .position(|&(_, i)| i == BACKDROP || opaque[i])
                {
                    sc.order.truncate(p + 1);
                }
                piece(a, b, &sc.order, frags);
            }
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
    links: &[Link],
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
    let mut cuts = std::mem::take(&mut sc.element_cuts);
    sort(frags);
    let mut opaque = std::mem::take(&mut sc.opaque);
    opaque.clear();
    opaque.extend(frags.iter().map(|f| layers.opaque(f)));
    sweep(
        frags,
        links,
        bg,
        &opaque,
        breaks,
        sc,
        |a, b, order, frags| {
            if !ref_done && t_ref >= a && t_ref <= b {
                ref_done = true;
                out.front = match order.first() {
                    Some(&(_, i)) if i != BACKDROP => Some((i, depth_at(&frags[i], links, t_ref))),
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
            // filter-weighted mean over the piece is itself (whichever triangle of a chain covers
            // the sample).
            if let Some(c) = composite_uniform(order, frags, bg, layers) {
                for j in 0..4 {
                    acc[j] += dw * c[j];
                }
                return;
            }
            // Cut where a layer's chain passes from one triangle to the next: every sub-piece is
            // shaded by the same triangles throughout.
            cuts.clear();
            cuts.push(a);
            let mut chained = 0;
            for &(_, i) in order {
                if i != BACKDROP && frags[i].n > 1 {
                    let before = cuts.len();
                    layers.cuts(i, &frags[i], a, b, &mut cuts);
                    chained += usize::from(cuts.len() > before);
                }
            }
            cuts.push(b);
            // each layer's cuts come ascending; several layers' cuts interleave
            if chained > 1 {
                let n = cuts.len();
                cuts[1..n - 1].sort_unstable_by(f64::total_cmp);
            }
            for c in 0..cuts.len() - 1 {
                let (u, v) = (cuts[c], cuts[c + 1]);
                if v <= u {
                    continue;
                }
                let dw = if cuts.len() == 2 {
                    dw
                } else {
                    weight(shutter, u, v)
                };
                if dw <= 0.0 {
                    continue;
                }
                let (xs, ws) = gauss(quad.points(v - u));
                let (half, mid) = (0.5 * (v - u), 0.5 * (u + v));
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
            }
        },
    );
    sc.opaque = opaque;
    sc.element_cuts = cuts;
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
        fn cuts(&mut self, _i: usize, _f: &Frag, _a: f64, _b: f64, _out: &mut Vec<f64>) {}
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

    const LINK: [Link; 1] = [Link {
        t0: 0.0,
        z0: 0.0,
        prim: 0,
        next: super::NONE,
    }];

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
            &LINK,
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
            &LINK,
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
            &LINK,
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
            &LINK,
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
            &LINK,
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
