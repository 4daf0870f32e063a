//! Coverage alphas of the motion volume for the `box`, `triangle` and `gaussian` shutter filters
//! (our own design; the paper only states its ramp, see [`Filter`]).
//!
//! The physically correct time-averaged image of an object gives a pixel the weighted fraction of
//! the shutter during which the object covers it, `integral of w(t) [pixel covered at t] dt`, and
//! its total coverage equals the object's projected area (the shutter weight `w` has unit
//! integral). A motion volume drawn with back-face culling shows one surface per pixel, so its
//! per-vertex alpha should be that fraction at the vertex's image position. We compute it with a
//! 2D model of the view:
//!
//! - the view is an orthographic projection along `view` (from the camera to the object's
//!   centroid at mid-shutter; without a camera, along the world axis least aligned with the
//!   motion, made perpendicular to it);
//! - with a camera the projection is perspective, onto a picture plane perpendicular to `view`;
//!   for a translation `view` is first made perpendicular to the motion (unless they are within
//!   37 degrees), so that the plane is parallel to the motion and every image point moves along
//!   parallel lines, as the translated hull below assumes (on the camera's own plane the paths
//!   converge to the motion's vanishing point and a rim moving along itself would be swept
//!   across); without a camera it is orthographic;
//! - during path segment `j` (keyframes `j` and `j + 1`, times `t_j .. t_{j+1}`) the object's
//!   image is the convex hull `S_j` of its projected vertices placed at mid-segment, translated
//!   linearly by the projected displacement `d_j` of the centroid (for a translation path seen
//!   orthographically every `S_j` is `S_0` moved, and this is exact for a convex object);
//! - a point `p` of the image is covered at `t = t_j + u (t_{j+1} - t_j)` iff
//!   `p - (u - 1/2) d_j` lies in `S_j`, an interval of `u` read from the chord of `S_j` along
//!   `d_j` through `p`; its filter weight is `W(t_hi) - W(t_lo)` with `W` the cumulative
//!   weight, summed over the segments.
//!
//! Along a joining strip this fraction has kinks where the object's ends pass the point, so each
//! segment of the strip is cut, per contour vertex, at those two times (see [`CoverageModel::knots`])
//! and at `q - 1` equally spaced times (`q` from [`Filter::knots_per_segment`]) for the curvature
//! of the triangle and gaussian weights. The chord tables hold 1024 rows per segment (fewer for
//! long paths, at least 64).
//!
//! A path of more than [`MAX_MODEL_SEGMENTS`] segments is followed on that many spans of
//! consecutive segments (each span's hull at its middle, moved along the chord between its
//! ends): a vertex's coverage then costs the same for any number of segments, and a volume's
//! alphas cost time linear in its segments. Its strips are still cut per path segment, each
//! with its span's hull moved to the segment's middle.

use super::filter::Filter;
use super::hulls::{hulls_of, project};
use super::rim::Rim;
use crate::mesh::{dot, normalize};
use crate::motion::{Keyframe, Path};

/// The chord of a convex polygon along a direction: for rows of constant `y` (across the
/// direction), the interval `[lo, hi]` of `x` (along it) inside the polygon. A polygon of at
/// most [`EXACT_HULL`] vertices keeps its edges and answers exactly; a larger one is tabulated.
#[derive(Debug, Clone)]
struct ChordTable {
    y0: f64,
    dy: f64,
    lo: Vec<f64>,
    hi: Vec<f64>,
    /// The edges `(a, b)` with `a.y <= b.y`, for a small polygon (then `lo`, `hi` are empty).
    edges: Vec<([f64; 2], [f64; 2])>,
}

/// Largest hull answered edge by edge instead of by a table (a box's hull has at most 8).
const EXACT_HULL: usize = 16;

impl ChordTable {
    /// `hull`: convex polygon (any orientation) in (x, y) coordinates.
    fn new(hull: &[[f64; 2]], rows: usize) -> Option<Self> {
        let (ymin, ymax) = hull
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p[1]), b.max(p[1]))
            });
        if hull.len() < 3 || ymax.is_nan() || ymax <= ymin {
            return None;
        }
        if hull.len() <= EXACT_HULL {
            let edges = hull
                .iter()
                .zip(hull.iter().cycle().skip(1))
                .map(|(p, q)| if p[1] <= q[1] { (*p, *q) } else { (*q, *p) })
                .collect();
            return Some(ChordTable {
                y0: ymin,
                dy: ymax - ymin,
                lo: Vec::new(),
                hi: Vec::new(),
                edges,
            });
        }
        let dy = (ymax - ymin) / rows as f64;
        let mut lo = vec![f64::INFINITY; rows];
        let mut hi = vec![f64::NEG_INFINITY; rows];
        for (i, p) in hull.iter().enumerate() {
            let q = hull[(i + 1) % hull.len()];
            let (a, b) = if p[1] <= q[1] { (*p, q) } else { (q, *p) };
            let k0 = ((a[1] - ymin) / dy - 0.5).ceil().max(0.0) as usize;
            let k1 = ((b[1] - ymin) / dy - 0.5).floor().min(rows as f64 - 1.0);
            if k1 < 0.0 {
                continue;
            }
            for s in k0..=(k1 as usize) {
                let y = ymin + (s as f64 + 0.5) * dy;
                let (x0, x1) = if b[1] > a[1] {
                    let x = a[0] + (b[0] - a[0]) * ((y - a[1]) / (b[1] - a[1])).clamp(0.0, 1.0);
                    (x, x)
                } else {
                    (a[0].min(b[0]), a[0].max(b[0]))
                };
                lo[s] = lo[s].min(x0);
                hi[s] = hi[s].max(x1);
            }
        }
        // Every row centre lies inside [ymin, ymax], so each row is crossed by the polygon.
        for s in 0..rows {
            if lo[s] > hi[s] {
                let (l, h) = if s > 0 {
                    (lo[s - 1], hi[s - 1])
                } else {
                    (0.0, -1.0)
                };
                lo[s] = l;
                hi[s] = h;
            }
        }
        Some(ChordTable {
            y0: ymin,
            dy,
            lo,
            hi,
            edges: Vec::new(),
        })
    }

    /// `[lo, hi]` at `y`: exact for a small polygon, else linear between row centres; `None`
    /// outside the polygon's rows.
    fn chord(&self, y: f64) -> Option<(f64, f64)> {
        if !self.edges.is_empty() {
            if !(self.y0..=self.y0 + self.dy).contains(&y) {
                return None;
            }
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for (a, b) in &self.edges {
                if a[1] <= y && y <= b[1] {
                    let (x0, x1) = if b[1] > a[1] {
                        let x = a[0] + (b[0] - a[0]) * ((y - a[1]) / (b[1] - a[1]));
                        (x, x)
                    } else {
                        (a[0].min(b[0]), a[0].max(b[0]))
                    };
                    lo = lo.min(x0);
                    hi = hi.max(x1);
                }
            }
            return (hi >= lo).then_some((lo, hi));
        }
        let n = self.lo.len();
        let f = (y - self.y0) / self.dy;
        if !(0.0..=n as f64).contains(&f) {
            return None;
        }
        let g = (f - 0.5).clamp(0.0, (n - 1) as f64);
        let k = (g.floor() as usize).min(n.saturating_sub(2));
        let w = if n > 1 { g - k as f64 } else { 0.0 };
        let k1 = (k + 1).min(n - 1);
        let lo = self.lo[k] + (self.lo[k1] - self.lo[k]) * w;
        let hi = self.hi[k] + (self.hi[k1] - self.hi[k]) * w;
        (hi >= lo).then_some((lo, hi))
    }
}

/// Above this many vertices a translation's coverage model uses 3 sub-segments instead of 8
/// (each one projects every vertex and takes its hull).
const DENSE_VERTICES: usize = 20_000;

/// Most spans the model follows a path on: a longer path's segments are taken in this many
/// consecutive groups (see [`spans`]), so that a vertex's coverage costs the same for any number
/// of segments.
pub const MAX_MODEL_SEGMENTS: usize = 64;

/// The spans `(a, b)` of keyframes the model follows a path of `n` segments on: every segment,
/// or past [`MAX_MODEL_SEGMENTS`] that many groups of consecutive ones.
fn spans(n: usize) -> Vec<(usize, usize)> {
    if n > MAX_MODEL_SEGMENTS {
        let m = MAX_MODEL_SEGMENTS;
        (0..m).map(|g| (g * n / m, (g + 1) * n / m)).collect()
    } else {
        (0..n).map(|j| (j, j + 1)).collect()
    }
}

/// The placement of `p` at the middle of the span `(a, b)` (in time).
fn middle(p: &Path, (a, b): (usize, usize)) -> Keyframe {
    if b == a + 1 {
        p.between(a, 0.5)
    } else {
        p.between((a + b) / 2, if (a + b) % 2 == 1 { 0.5 } else { 0.0 })
    }
}

/// One path segment of the model.
#[derive(Debug, Clone)]
struct Segment {
    t0: f64,
    t1: f64,
    /// Unit direction of the projected displacement, its perpendicular, and its length.
    dir: [f64; 2],
    perp: [f64; 2],
    len: f64,
    table: Option<ChordTable>,
}

/// The 2D coverage model of a mesh moving along a path (see the module docs).
#[derive(Debug, Clone)]
pub struct CoverageModel {
    filter: Filter,
    /// Perspective centre (the camera), or `None` for an orthographic view along `d`.
    eye: Option<[f64; 3]>,
    d: [f64; 3],
    e1: [f64; 3],
    e2: [f64; 3],
    segments: Vec<Segment>,
    /// The segments of the path itself (for [`CoverageModel::knots`]).
    geometric: Vec<Segment>,
    /// Below this projected length a segment counts as not moving (scene units).
    still: f64,
    /// The part of the shutter the path stands for, its filter weight (see
    /// [`CoverageModel::windowed`]).
    window: (f64, f64),
    window_weight: f64,
}

fn cross3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The default view: the world axis least aligned with `motion`, made perpendicular to it.
pub fn default_view(motion: [f64; 3]) -> [f64; 3] {
    let m = normalize(motion);
    if m == [0.0; 3] {
        return [0.0, 0.0, -1.0];
    }
    let k = (0..3)
        .min_by(|&a, &b| m[a].abs().total_cmp(&m[b].abs()))
        .expect("three axes");
    let mut axis = [0.0; 3];
    axis[k] = -1.0;
    let c = dot(axis, m);
    normalize([axis[0] - c * m[0], axis[1] - c * m[1], axis[2] - c * m[2]])
}

/// Whether two placements are the same up to rounding (relative 1e-12).
fn same_placement(a: &Keyframe, b: &Keyframe) -> bool {
    let scale = 1.0 + a.translation.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let lin = a.linear.iter().flatten().zip(b.linear.iter().flatten());
    let tr = a.translation.iter().zip(&b.translation);
    lin.chain(tr).all(|(x, y)| (x - y).abs() <= 1e-12 * scale)
}

/// The unit view direction `d` (along -z when `view` is zero) and the image axes `e1`, `e2`
/// across it.
fn view_axes(view: [f64; 3]) -> [[f64; 3]; 3] {
    let d = normalize(view);
    let d = if d == [0.0; 3] { [0.0, 0.0, -1.0] } else { d };
    let helper = if d[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let e1 = normalize(cross3(helper, d));
    let e2 = cross3(d, e1);
    [d, e1, e2]
}

/// What [`CoverageModel::new`] builds its segments from: the projection, the hulls of the
/// mesh at every placement the segments ask for, and the path of its centroid.
struct Segments<'a> {
    path: &'a Path,
    eye: Option<[f64; 3]>,
    /// `d`, `e1`, `e2` (see [`view_axes`]).
    axes: [[f64; 3]; 3],
    centroid: [f64; 3],
    /// Orthographic translation: every segment's silhouette is the first one moved.
    pure: bool,
    /// The distinct placements the hulls were taken at, and the hulls.
    placements: Vec<Keyframe>,
    hulls: Vec<Vec<[f64; 2]>>,
    /// The orthographic translation's (first) hull.
    base: Option<Vec<[f64; 2]>>,
    /// Below this projected length a segment counts as not moving.
    still: f64,
}

impl<'a> Segments<'a> {
    /// The hulls of `vertices` (with `rim`, see [`CoverageModel::new`]) placed along `path`
    /// at the middle of every span of its segments and of `sub`'s, seen along `axes`.
    fn new(
        vertices: &[[f64; 3]],
        rim: Option<Rim>,
        path: &'a Path,
        sub: Option<&Path>,
        eye: Option<[f64; 3]>,
        axes: [[f64; 3]; 3],
    ) -> Self {
        let k = vertices.len() as f64;
        let centroid = {
            let s = vertices
                .iter()
                .fold([0.0; 3], |a, v| [a[0] + v[0], a[1] + v[1], a[2] + v[2]]);
            [s[0] / k, s[1] / k, s[2] / k]
        };
        let pure = path.is_translation() && eye.is_none();
        // Hulls by placement: the middle sub-segment of an odd subdivision is placed (up to
        // rounding) where its path segment's middle is, and shares that hull (the first
        // placement asked for, in the order the segments ask).
        let mids = |p: &Path| -> Vec<Keyframe> {
            spans(p.segments())
                .into_iter()
                .map(|s| middle(p, s))
                .collect()
        };
        let mut placements: Vec<Keyframe> = Vec::new();
        let wanted = if pure {
            vec![path.frames[0]]
        } else {
            let mut w = mids(path);
            w.extend(sub.map(mids).unwrap_or_default());
            w
        };
        for f in wanted {
            if !placements.iter().any(|k| same_placement(k, &f)) {
                placements.push(f);
            }
        }
        let hulls = hulls_of(vertices, rim, &placements, eye, axes);
        let mut segments = Segments {
            path,
            eye,
            axes,
            centroid,
            pure,
            placements,
            hulls,
            base: None,
            still: 0.0,
        };
        segments.base = pure.then(|| segments.hull_at(&path.frames[0]));
        let size = segments
            .base
            .as_ref()
            .map(|h| {
                h.iter()
                    .map(|p| p[0].abs().max(p[1].abs()))
                    .fold(0.0, f64::max)
            })
            .unwrap_or(1.0);
        segments.still = 1e-12 * size.max(1e-300);
        segments
    }

    fn proj(&self, p: [f64; 3]) -> [f64; 2] {
        let [d, e1, e2] = self.axes;
        project(self.eye, d, e1, e2, p)
    }

    /// The hull at placement `f` (that of the first same placement).
    fn hull_at(&self, f: &Keyframe) -> Vec<[f64; 2]> {
        let k = self
            .placements
            .iter()
            .position(|k| same_placement(k, f))
            .unwrap_or(0);
        self.hulls[k].clone()
    }

    /// The projected path of span (a, b) of `p`: its ends' images (the translation's, or the
    /// centroid's placed).
    fn ends(&self, p: &Path, (a, b): (usize, usize)) -> ([f64; 2], [f64; 2]) {
        let (fa, fb) = (&p.frames[a], &p.frames[b]);
        if self.pure {
            (self.proj(fa.translation), self.proj(fb.translation))
        } else {
            (
                self.proj(fa.point(self.centroid)),
                self.proj(fb.point(self.centroid)),
            )
        }
    }

    /// The segment of span (a, b) of `p` with the image `hull` at its middle, its chord table
    /// of `rows` rows.
    fn make(&self, p: &Path, (a, b): (usize, usize), hull: Vec<[f64; 2]>, rows: usize) -> Segment {
        let n = p.segments();
        let (pa, pb) = self.ends(p, (a, b));
        let disp = [pb[0] - pa[0], pb[1] - pa[1]];
        let len = (disp[0] * disp[0] + disp[1] * disp[1]).sqrt();
        let dir = if len > self.still {
            [disp[0] / len, disp[1] / len]
        } else {
            [1.0, 0.0]
        };
        let perp = [-dir[1], dir[0]];
        let local: Vec<[f64; 2]> = hull
            .iter()
            .map(|p| {
                [
                    p[0] * dir[0] + p[1] * dir[1],
                    p[0] * perp[0] + p[1] * perp[1],
                ]
            })
            .collect();
        Segment {
            t0: a as f64 / n as f64,
            t1: b as f64 / n as f64,
            dir,
            perp,
            len,
            table: ChordTable::new(&local, rows),
        }
    }

    /// The orthographic translation's hull `h` (the first one) moved to the span's middle.
    fn moved(&self, p: &Path, span: (usize, usize), h: &[[f64; 2]]) -> Vec<[f64; 2]> {
        let (pa, pb) = self.ends(p, span);
        let o = self.proj(self.path.frames[0].translation);
        let off = [0.5 * (pa[0] + pb[0]) - o[0], 0.5 * (pa[1] + pb[1]) - o[1]];
        h.iter().map(|q| [q[0] + off[0], q[1] + off[1]]).collect()
    }

    /// One segment per span of `p`'s segments, with the hull at the span's middle.
    fn build(&self, p: &Path) -> Vec<Segment> {
        let spans = spans(p.segments());
        let rows = (65_536 / spans.len().max(1)).clamp(64, 1024);
        spans
            .into_iter()
            .map(|span| {
                let hull = match &self.base {
                    Some(h) => self.moved(p, span, h),
                    None => self.hull_at(&middle(p, span)),
                };
                self.make(p, span, hull, rows)
            })
            .collect()
    }

    /// Every segment of the path (more than `MAX_MODEL_SEGMENTS`), with the hull of its span
    /// moved by the centroid's image from the span's middle to the segment's (as the model
    /// moves a hull along its span).
    fn every_segment(&self) -> Vec<Segment> {
        let path = self.path;
        let n = path.segments();
        let rows = (65_536 / n).clamp(64, 1024);
        let groups = spans(n);
        let centres: Vec<[f64; 2]> = groups
            .iter()
            .map(|&g| self.proj(middle(path, g).point(self.centroid)))
            .collect();
        let group_hulls: Vec<Vec<[f64; 2]>> = match &self.base {
            Some(_) => Vec::new(),
            None => groups
                .iter()
                .map(|&g| self.hull_at(&middle(path, g)))
                .collect(),
        };
        let mut g = 0;
        (0..n)
            .map(|j| {
                while groups[g].1 <= j {
                    g += 1;
                }
                let hull = match &self.base {
                    Some(h) => self.moved(path, (j, j + 1), h),
                    None => {
                        let (pa, pb) = self.ends(path, (j, j + 1));
                        let c = centres[g];
                        let off = [0.5 * (pa[0] + pb[0]) - c[0], 0.5 * (pa[1] + pb[1]) - c[1]];
                        group_hulls[g]
                            .iter()
                            .map(|q| [q[0] + off[0], q[1] + off[1]])
                            .collect()
                    }
                };
                self.make(path, (j, j + 1), hull, rows)
            })
            .collect()
    }
}

impl CoverageModel {
    /// The model of `vertices` (object space) placed along `path` and seen along `view`, from
    /// the camera at `eye` (perspective) or orthographically. With `rim` (the faces of a closed
    /// mesh on these vertices) each hull is taken over the projected silhouette only
    /// ([`rim_points`](super::rim::rim_points)), unless a vertex is not in front of the eye.
    pub fn new(
        vertices: &[[f64; 3]],
        rim: Option<Rim>,
        path: &Path,
        filter: Filter,
        view: [f64; 3],
        eye: Option<[f64; 3]>,
    ) -> Self {
        let axes = view_axes(view);
        let n = path.segments();
        // Under perspective the silhouette changes along the path and its points move at speeds
        // that differ with depth, so the coverage integral follows it on at least 8
        // sub-segments; a translated dense mesh (hull of many points per sub-segment) gets 3;
        // an orthographic translation needs no more than the path's.
        // The cuts of the joining strips use the path's own segments.
        let pure = path.is_translation() && eye.is_none();
        let parts = if pure || n > MAX_MODEL_SEGMENTS {
            1
        } else if path.is_translation() && vertices.len() > DENSE_VERTICES {
            3usize.div_ceil(n)
        } else {
            8usize.div_ceil(n)
        };
        let sub = (parts > 1).then(|| path.subdivide(parts));
        let s = Segments::new(vertices, rim, path, sub.as_ref(), eye, axes);
        let segments = s.build(sub.as_ref().unwrap_or(path));
        let geometric = if n > MAX_MODEL_SEGMENTS {
            s.every_segment()
        } else if sub.is_some() {
            s.build(path)
        } else {
            segments.clone()
        };
        let [d, e1, e2] = axes;
        CoverageModel {
            filter,
            eye,
            d,
            e1,
            e2,
            segments,
            geometric,
            still: s.still,
            window: (0.0, 1.0),
            window_weight: 1.0,
        }
    }

    /// The model with the path standing for the part `(a, b)` of the shutter (its times `t` are
    /// the shutter times `a + (b - a) t`): the coverage weighs the time by the filter over
    /// `[a, b]`, normalised to unit weight (`(0, 1)`: the whole shutter, the default). The
    /// window must have a positive weight (see `check_options`).
    pub fn windowed(mut self, (a, b): (f64, f64)) -> Self {
        self.window = (a, b);
        self.window_weight = self.filter.weight(a, b);
        self
    }

    /// The filter weight of the path times `[t0, t1]` within the window, normalised.
    #[inline]
    fn weight(&self, t0: f64, t1: f64) -> f64 {
        let (a, b) = self.window;
        if (a, b) == (0.0, 1.0) {
            return self.filter.cumulative(t1) - self.filter.cumulative(t0);
        }
        let span = b - a;
        self.filter.weight(a + t0 * span, a + t1 * span) / self.window_weight
    }

    fn local(&self, s: &Segment, p: [f64; 3]) -> (f64, f64) {
        Self::rotated(s, project(self.eye, self.d, self.e1, self.e2, p))
    }

    /// The image point `q` in the segment's frame (along its motion, across it).
    #[inline]
    fn rotated(s: &Segment, q: [f64; 2]) -> (f64, f64) {
        (
            q[0] * s.dir[0] + q[1] * s.dir[1],
            q[0] * s.perp[0] + q[1] * s.perp[1],
        )
    }

    /// The image of the world point `p` on the model's picture plane (the units of its hulls).
    pub fn image(&self, p: [f64; 3]) -> [f64; 2] {
        project(self.eye, self.d, self.e1, self.e2, p)
    }

    /// The filter-weighted fraction of the shutter during which the object covers the image of
    /// the world point `p`, in [0, 1].
    pub fn coverage(&self, p: [f64; 3]) -> f64 {
        let mut sum = 0.0;
        // One projection for every segment (the view does not change along the path).
        let q = project(self.eye, self.d, self.e1, self.e2, p);
        for s in &self.segments {
            let Some(table) = &s.table else { continue };
            let (x, y) = Self::rotated(s, q);
            let Some((a, b)) = table.chord(y) else {
                continue;
            };
            let (u0, u1) = if s.len > self.still {
                (
                    (0.5 + (x - b) / s.len).max(0.0),
                    (0.5 + (x - a) / s.len).min(1.0),
                )
            } else if (a..=b).contains(&x) {
                (0.0, 1.0)
            } else {
                continue;
            };
            if u1 > u0 {
                let dt = s.t1 - s.t0;
                sum += self.weight(s.t0 + u0 * dt, s.t0 + u1 * dt);
            }
        }
        sum.clamp(0.0, 1.0)
    }

    /// Cut points in (0, 1) of segment `j`'s joining strip for a contour point placed at `p0`
    /// (segment start) and `p1` (segment end): the two times at which the object's front and
    /// back ends pass it (from its own image motion, which under perspective differs from the
    /// silhouette's), and `q - 1` equally spaced times; sorted, always `q + 1` of them (clipped
    /// ones repeat an end).
    pub fn knots(&self, j: usize, p0: [f64; 3], p1: [f64; 3], q: usize) -> Vec<f64> {
        let s = &self.geometric[j];
        let mut out: Vec<f64> = (1..q).map(|k| k as f64 / q as f64).collect();
        let mut kinks = [0.5 / q as f64, 1.0 - 0.5 / q as f64];
        if let (Some(table), true) = (&s.table, s.len > self.still) {
            let (x0, y0) = self.local(s, p0);
            let (x1, y1) = self.local(s, p1);
            let dx = x1 - x0;
            if let (Some((a, b)), true) = (table.chord(0.5 * (y0 + y1)), dx.abs() > self.still) {
                // Window of P(u) = x0 + u dx: [u + 0.5 + (x0 - b)/len, ...]; start hits 0, end hits 1.
                kinks = [
                    ((b - x0 - 0.5 * s.len) / dx).clamp(0.0, 1.0),
                    ((a + 0.5 * s.len - x0) / dx).clamp(0.0, 1.0),
                ];
            }
        }
        out.extend(kinks);
        out.sort_by(f64::total_cmp);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Vec<[f64; 3]> {
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ]
    }

    #[test]
    fn box_coverage_of_a_translating_square_is_exact() {
        // A unit square moving 4 along x, seen along -z: a point at x covers the window where the
        // square's [tx, tx + 1] contains it, so coverage = |[x - 1, x] / 4 ∩ [0, 1]|.
        let path = Path::translation([4.0, 0.0, 0.0]).unwrap();
        let m = CoverageModel::new(&square(), None, &path, Filter::Box, [0.0, 0.0, -1.0], None);
        for (x, want) in [
            (-0.5, 0.0),
            (0.5, 0.125),
            (2.0, 0.25),
            (4.5, 0.125),
            (5.5, 0.0),
        ] {
            let got = m.coverage([x, 0.5, 0.0]);
            assert!((got - want).abs() < 1e-9, "x {x}: {got} vs {want}");
        }
        assert_eq!(m.coverage([2.0, 1.5, 0.0]), 0.0);
        let k = m.knots(0, [0.0, 0.5, 0.0], [4.0, 0.5, 0.0], 1);
        assert!((k[0] - 0.25).abs() < 1e-12 && (k[1] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn a_window_weighs_its_part_of_the_shutter() {
        // The rising half of the triangle filter, normalised, is the weight 2u on the path's
        // time u: the ramp's cumulative u^2. A box window is the box itself.
        let path = Path::translation([4.0, 0.0, 0.0]).unwrap();
        let model =
            |f: Filter| CoverageModel::new(&square(), None, &path, f, [0.0, 0.0, -1.0], None);
        let half = model(Filter::Triangle).windowed((0.0, 0.5));
        let ramp = model(Filter::Ramp);
        let boxed = model(Filter::Box).windowed((0.3, 0.7));
        for x in [-0.5, 0.3, 0.5, 1.7, 2.0, 3.2, 4.5] {
            let p = [x, 0.5, 0.0];
            assert!((half.coverage(p) - ramp.coverage(p)).abs() < 1e-12, "x {x}");
            assert!((boxed.coverage(p) - model(Filter::Box).coverage(p)).abs() < 1e-12);
        }
        assert!(half.coverage([3.5, 0.5, 0.0]) > 0.2);
    }
}
