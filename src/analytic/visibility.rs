//! Visibility over time at one sample: which fragments are in front, and in what order, on
//! each piece of the shutter.
//!
//! A sample holds fragments: the spans of shutter time during which one triangle covers it,
//! with the triangle's view depth at both ends (linear in between). A fragment may stand for a
//! run of triangles of one surface that cover the sample one after the other (a chain, see
//! `tiles.rs`); each link keeps its own depth at its start, so the chain's depth is linear per
//! link, exactly as the separate spans would be. [`sweep`] cuts the shutter at every fragment
//! end, at every link of a chain present with other layers, at every instant where two layers
//! (or a layer and the static backdrop) cross in depth, and at the filter's kinks; on each
//! resulting piece the depth order is fixed.
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

/// A sample's lists would outgrow the memory budget they were given.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Overflow;

/// The static layer (the frame's backdrop) at one sample: the opaque colour behind the moving
/// triangles, its depth and id.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StaticSample {
    /// Premultiplied RGBA.
    pub rgba: [f32; 4],
    /// View depth, `inf` where nothing is there.
    pub depth: f32,
    /// Object id, -1 where nothing is there.
    pub id: i32,
}

/// Per-thread buffers of [`sweep`], kept across samples, and its limit.
pub struct Sweep {
    active: Vec<usize>,
    cuts: Vec<f64>,
    order: Vec<(f64, usize)>,
    sub: Vec<f64>,
    lines: Vec<(usize, [f64; 4])>,
    cursor: Vec<u32>,
    /// Per fragment: whether its every depth lies in front of the backdrop ([`AHEAD`]), not
    /// ([`BEHIND`]), or not yet known (0).
    ahead: Vec<u8>,
    /// Whether a stretch of one fragment alone in front of the backdrop (whose order cannot
    /// change) is given as one piece, not one per link of its chain: for a caller that joins
    /// touching pieces of the same layers anyway and notes nothing per piece (off by default).
    pub joined: bool,
    /// Most depth crossings the layers present together over one stretch of time may have
    /// (unlimited by default).
    pub max_cuts: usize,
}

impl Default for Sweep {
    fn default() -> Self {
        Sweep {
            active: Vec::new(),
            cuts: Vec::new(),
            order: Vec::new(),
            sub: Vec::new(),
            lines: Vec::new(),
            cursor: Vec::new(),
            ahead: Vec::new(),
            joined: false,
            max_cuts: usize::MAX,
        }
    }
}

impl Sweep {
    /// Cuts `[u, v]` where an active chain passes from one link to the next, into `sub`
    /// (ascending, from `u` to `v`): every layer's depth is one straight piece between cuts.
    #[inline(always)]
    fn link_cuts(&mut self, frags: &[Frag], links: &[Link], u: f64, v: f64) {
        self.sub.clear();
        self.sub.push(u);
        for &i in &self.active {
            if frags[i].n > 1 {
                let mut c = frags[i].chain;
                while let Some(next) = Some(links[c as usize].next).filter(|&x| x != NONE) {
                    let t = f64::from(links[next as usize].t0);
                    if t >= v {
                        break;
                    }
                    if t > u {
                        self.sub.push(t);
                    }
                    c = next;
                }
            }
        }
        self.sub.push(v);
        if self.sub.len() > 3 {
            sort_times(&mut self.sub[1..]);
        }
    }

    /// Cuts `[p, q]` where any two of the straight `lines` cross in depth, into `cuts`
    /// (ascending, from `p` to `q`); [`Overflow`] past `max_cuts` crossings.
    #[inline(always)]
    fn crossing_cuts(&mut self, p: f64, q: f64) -> Result<(), Overflow> {
        self.cuts.clear();
        self.cuts.push(p);
        for a in 0..self.lines.len() {
            for b in a + 1..self.lines.len() {
                let (la, lb) = (&self.lines[a].1, &self.lines[b].1);
                let g0 = line_at(la, p) - line_at(lb, p);
                let g1 = line_at(la, q) - line_at(lb, q);
                if (g0 < 0.0 && g1 > 0.0) || (g0 > 0.0 && g1 < 0.0) {
                    let x = p + (q - p) * (g0 / (g0 - g1));
                    if x > p && x < q {
                        if self.cuts.len() > self.max_cuts {
                            return Err(Overflow);
                        }
                        self.cuts.push(x);
                    }
                }
            }
        }
        self.cuts.push(q);
        if self.cuts.len() > 3 {
            sort_times(&mut self.cuts[1..]);
        }
        Ok(())
    }
}

/// The depth of the straight piece `l` = `[t_a, z_a, t_b, z_b]` at time `t` (clamped to it).
#[inline(always)]
fn line_at(l: &[f64; 4], t: f64) -> f64 {
    if l[2] > l[0] {
        // at its ends the fraction is exactly 0 (`0 / x`) or 1 (`x / x`): no division there
        let f = if t == l[0] {
            0.0
        } else if t == l[2] {
            1.0
        } else {
            ((t - l[0]) / (l[2] - l[0])).clamp(0.0, 1.0)
        };
        l[1] + (l[3] - l[1]) * f
    } else {
        l[1]
    }
}

/// [`Sweep::ahead`]: a fragment in front of the backdrop throughout, or not.
const AHEAD: u8 = 1;
const BEHIND: u8 = 2;

/// Whether every depth of fragment `f`'s chain (its ends and each link's start) lies in front
/// of depth `z`: then so does its depth at any time (linear between them per link; the depths
/// are single precision, so the gap to `z` is far wider than the rounding of `line_at`).
fn chain_ahead(f: &Frag, links: &[Link], z: f32) -> bool {
    if !(f.z0 < z && f.z1 < z) {
        return false;
    }
    let mut c = f.chain;
    loop {
        let l = &links[c as usize];
        if !(l.z0 < z) {
            return false;
        }
        if l.next == NONE {
            return true;
        }
        c = l.next;
    }
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

/// Sorts `v` ascending by `less`, a strict order under which no two different items are equal
/// (so any sort gives the same result): by insertion for the few items a sample's lists hold
/// (the library's sort costs more in set-up than these lists take to sort), else the library's.
#[inline(always)]
pub fn sort_small<T: Copy>(v: &mut [T], less: impl Fn(&T, &T) -> bool) {
    if v.len() > 16 {
        v.sort_unstable_by(|a, b| {
            if less(a, b) {
                std::cmp::Ordering::Less
            } else if less(b, a) {
                std::cmp::Ordering::Greater
            } else {
                std::cmp::Ordering::Equal
            }
        });
        return;
    }
    for i in 1..v.len() {
        let x = v[i];
        let mut j = i;
        while j > 0 && less(&x, &v[j - 1]) {
            v[j] = v[j - 1];
            j -= 1;
        }
        v[j] = x;
    }
}

/// Sorts instants ascending by [`f64::total_cmp`] (items it finds equal have the same bits, so
/// any sort gives the same result).
#[inline(always)]
pub fn sort_times(v: &mut [f64]) {
    sort_small(v, |a, b| a.total_cmp(b).is_lt());
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

/// Walks the shutter over the fragments of one sample (sorted by [`sort`]) in pieces of fixed
/// depth order:
/// `piece(a, b, layers)` gets each piece `[a, b]` with its layers front to back (fragment
/// indices, or `BACKDROP`), cut after the first opaque one. Pieces with no layer are skipped.
/// `breaks` are extra instants to cut at. Fails with [`Overflow`] where the layers present
/// together over one stretch of time cross in depth more than `sc.max_cuts` times (the
/// instants would take more memory than the caller's budget).
#[inline(always)]
pub fn sweep(
    frags: &[Frag],
    links: &[Link],
    bg: &StaticSample,
    opaque: &[bool],
    breaks: &[f64],
    sc: &mut Sweep,
    mut piece: impl FnMut(f64, f64, &[(f64, usize)], &[Frag]),
) -> Result<(), Overflow> {
    let has_bg = bg.depth.is_finite();
    sc.active.clear();
    sc.cursor.clear();
    sc.cursor.extend(frags.iter().map(|f| f.chain));
    sc.ahead.clear();
    sc.ahead.resize(frags.len(), 0);
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
        // One fragment in front of the backdrop throughout: no crossing to look for, the
        // order is known (what the general steps below find, without their depth tests).
        let alone = if n == 2 && has_bg {
            let i = sc.active[0];
            if sc.ahead[i] == 0 {
                sc.ahead[i] = if chain_ahead(&frags[i], links, bg.depth) {
                    AHEAD
                } else {
                    BEHIND
                };
            }
            (sc.ahead[i] == AHEAD).then_some(i)
        } else {
            None
        };
        if let (Some(i), true) = (alone, sc.joined) {
            sc.order.clear();
            sc.order.push((0.0, i));
            if !opaque[i] {
                sc.order.push((f64::from(bg.depth), BACKDROP));
            }
            piece(u, v, &sc.order, frags);
            continue;
        }
        // Chains change triangle (and depth slope) at their links: cut there first, so that
        // every layer's depth is one straight piece on each sub-interval.
        sc.link_cuts(frags, links, u, v);
        for k in 0..sc.sub.len() - 1 {
            let (p, q) = (sc.sub[k], sc.sub[k + 1]);
            if q <= p {
                continue;
            }
            let mid = 0.5 * (p + q);
            if let Some(i) = alone {
                let l = element_line(frags, links, &mut sc.cursor, i, mid);
                sc.order.clear();
                sc.order.push((line_at(&l, mid), i));
                if !opaque[i] {
                    sc.order.push((f64::from(bg.depth), BACKDROP));
                }
                piece(p, q, &sc.order, frags);
                continue;
            }
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
            // cut where any two layers cross in depth
            sc.crossing_cuts(p, q)?;
            for c in 0..sc.cuts.len() - 1 {
                let (a, b) = (sc.cuts[c], sc.cuts[c + 1]);
                if b <= a {
                    continue;
                }
                let m = 0.5 * (a + b);
                sc.order.clear();
                for (i, l) in &sc.lines {
                    sc.order.push((line_at(l, m), *i));
                }
                sort_small(&mut sc.order, |x, y| {
                    x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)).is_lt()
                });
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
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two chained links: depth 1 -> 3 over [0, 0.5] (prim 0), then 3 -> 1 over [0.5, 1] (prim 1).
    fn rising_then_falling() -> [Link; 2] {
        [
            Link {
                t0: 0.0,
                z0: 1.0,
                prim: 0,
                next: 1,
            },
            Link {
                t0: 0.5,
                z0: 3.0,
                prim: 1,
                next: NONE,
            },
        ]
    }

    /// The fragment of [`rising_then_falling`]'s chain over the whole shutter.
    fn chain_of_two() -> Frag {
        Frag {
            t0: 0.0,
            t1: 1.0,
            z0: 1.0,
            z1: 1.0,
            prim: 0,
            chain: 0,
            n: 2,
        }
    }

    #[test]
    fn a_chain_is_ordered_by_each_link_depth_not_by_its_ends() {
        // A chain of two triangles: depth 1 -> 3 over [0, 0.5], then 3 -> 1 over [0.5, 1].
        // Its ends are both at depth 1, so a straight line between them would keep it in front
        // of the flat fragment at depth 2 throughout; per link it is behind over (0.25, 0.75).
        let [l0, l1] = rising_then_falling();
        let links = [
            l0,
            l1,
            Link {
                t0: 0.0,
                z0: 2.0,
                prim: 2,
                next: NONE,
            },
        ];
        let chain = chain_of_two();
        let flat = Frag {
            t0: 0.0,
            t1: 1.0,
            z0: 2.0,
            z1: 2.0,
            prim: 2,
            chain: 2,
            n: 1,
        };
        assert_eq!(depth_at(&chain, &links, 0.5), 3.0);
        assert_eq!(depth_at(&chain, &links, 0.25), 2.0);
        assert_eq!(depth_at(&chain, &links, 0.875), 1.5);
        let frags = [chain, flat];
        let bg = StaticSample {
            rgba: [0.0; 4],
            depth: f32::INFINITY,
            id: -1,
        };
        let mut pieces = Vec::new();
        // one crossing per link: a budget of one crossing instant is enough, none is not
        let run = |max_cuts: usize, pieces: &mut Vec<(f64, f64, usize, usize)>| {
            sweep(
                &frags,
                &links,
                &bg,
                &[true, true],
                &[],
                &mut Sweep {
                    max_cuts,
                    ..Sweep::default()
                },
                |a, b, o, _| pieces.push((a, b, o[0].1, o.len())),
            )
        };
        assert_eq!(run(0, &mut Vec::new()), Err(Overflow));
        assert_eq!(run(1, &mut pieces), Ok(()));
        // front-most layer per piece, cut after the first opaque one
        let front: Vec<(f64, f64, usize)> = pieces.iter().map(|p| (p.0, p.1, p.2)).collect();
        assert_eq!(
            front,
            vec![
                (0.0, 0.25, 0),
                (0.25, 0.5, 1),
                (0.5, 0.75, 1),
                (0.75, 1.0, 0)
            ]
        );
        assert!(pieces.iter().all(|p| p.3 == 1));
    }

    #[test]
    fn a_chain_alone_over_the_backdrop_is_cut_at_its_links_or_where_it_crosses_it() {
        // A chain of two links, depth 1 -> 3 over [0, 0.5] and 3 -> 1 over [0.5, 1], alone over
        // the backdrop. Backdrop at depth 5: in front throughout (the short path, no depth
        // tests), one piece per link, or one in all when joined. Backdrop at depth 2: the chain
        // crosses it at 0.25 and 0.75 (the general path), and is behind over [0.25, 0.75].
        let links = rising_then_falling();
        let chain = chain_of_two();
        let run = |z: f32, opaque: bool, joined: bool| {
            let bg = StaticSample {
                rgba: [0.0; 4],
                depth: z,
                id: 7,
            };
            let mut pieces = Vec::new();
            sweep(
                &[chain],
                &links,
                &bg,
                &[opaque],
                &[],
                &mut Sweep {
                    joined,
                    ..Sweep::default()
                },
                |a, b, o, _| pieces.push((a, b, o.iter().map(|x| x.1).collect::<Vec<_>>())),
            )
            .unwrap();
            pieces
        };
        let front = vec![0];
        let both = vec![0, BACKDROP];
        assert_eq!(
            run(5.0, true, false),
            vec![(0.0, 0.5, front.clone()), (0.5, 1.0, front.clone())]
        );
        assert_eq!(
            run(5.0, false, false),
            vec![(0.0, 0.5, both.clone()), (0.5, 1.0, both.clone())]
        );
        // joined: the stretch as one piece of the same layers
        assert_eq!(run(5.0, true, true), vec![(0.0, 1.0, front.clone())]);
        assert_eq!(run(5.0, false, true), vec![(0.0, 1.0, both)]);
        let back = vec![BACKDROP];
        // crossing the backdrop: cut at the crossings, joined or not
        assert_eq!(run(2.0, true, true), run(2.0, true, false));
        assert_eq!(
            run(2.0, true, false),
            vec![
                (0.0, 0.25, front.clone()),
                (0.25, 0.5, back.clone()),
                (0.5, 0.75, back),
                (0.75, 1.0, front)
            ]
        );
    }

    #[test]
    fn sort_orders_by_start_then_triangle_whatever_the_input_order() {
        let f = |t0: f32, prim: u32| Frag {
            t0,
            t1: 1.0,
            z0: 1.0,
            z1: 1.0,
            prim,
            chain: 0,
            n: 1,
        };
        let want = [f(0.0, 1), f(0.0, 4), f(0.25, 0), f(0.5, 2)];
        for n in [4usize, 20] {
            // 24 fragments take the library sort, 8 the insertion sort
            let mut v: Vec<Frag> = (0..n).map(|k| f(0.75, 100 + k as u32)).collect();
            v.extend(want.iter().rev());
            let mut r = v.clone();
            r.reverse();
            sort(&mut v);
            sort(&mut r);
            assert_eq!(v, r);
            assert_eq!(&v[..4], &want);
        }
    }
}
