//! The segment rule: where the analytic method cuts the shutter so that every vertex moves
//! about linearly in clip space within a segment ([`segment_times`]).
//!
//! The shutter is first cut at every keyframe time of the objects' motions and of the camera's;
//! each piece is then halved while, at its middle, some test point lies more than `tolerance`
//! pixels from where motion linear in clip space between the piece's ends puts it, as far as it
//! can be seen (a point off the image or nearer than the near plane is measured as if it were
//! at the image's border and at the near plane). Test points are the corners of each rigid
//! object's bounding box and up to [`DEFORMING_POINTS`] vertices of each deforming one; a
//! deforming lambert object's piece is also halved while a test vertex's unit normal at the
//! middle lies more than [`NORMAL_TOLERANCE`] from the direction of the mean of its normals at
//! the ends. The piece furthest over its tolerance is halved first, up to [`MAX_SEGMENTS`]
//! segments, none halved below [`MIN_PIECE`].
//!
//! The arithmetic is the former numpy rule's, operation for operation (placements through
//! `motion::place`, normals through the mesh's own), so a still camera gives the same
//! boundaries bit for bit; a moving camera's view is inverted here, which may differ from
//! numpy's LAPACK inverse in the last bits.
use std::cmp::Ordering;
use std::collections::{BTreeSet, BinaryHeap, HashMap};

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::motion::{linear_part, place, row_times, translation_part};
use crate::motion::{Keyframes, Keys, Mat4, MovingCamera, IDENTITY4};

/// Most segments the rule makes.
pub const MAX_SEGMENTS: usize = 256;
/// Shortest piece the rule halves (a fraction of the shutter): halving a piece that never comes
/// straight (a point on a path with a kink, a NaN) would end in equal boundaries.
pub const MIN_PIECE: f64 = 1.0 / 1024.0;
/// Largest distance between a test vertex's unit normal at a piece's middle and the direction
/// of the mean of its normals at the piece's ends (about radians), for deforming lambert
/// objects: their normals are computed at every boundary and interpolated between, and lambert
/// shading moves by about this much wherever they bend.
pub const NORMAL_TOLERANCE: f64 = 2e-4;
/// Test vertices per deforming object.
pub const DEFORMING_POINTS: usize = 256;

/// One object the rule measures: its mesh (object space, or the rest pose of a deforming one),
/// its motion (None: still) and whether it is lambert shaded.
#[derive(Clone, Copy)]
pub struct SegmentObject<'a> {
    /// The object's mesh.
    pub mesh: &'a Mesh,
    /// Rigid keyframes placing the mesh, deforming ones (one position per mesh vertex), or None.
    pub motion: Option<&'a Keyframes>,
    /// Lambert shading (the normal-bend test applies to deforming lambert objects).
    pub lambert: bool,
}

/// The camera the rule measures in: the image's size, projection, pose and motion (`view`), its
/// near plane, and the scene camera's view-projection when still (as given, so that a still
/// camera's boundaries keep their bits). Matrices row-major.
#[derive(Clone, Copy)]
pub struct SegmentCamera<'a> {
    /// The image and the camera's motion.
    pub view: MovingCamera<'a>,
    /// The near plane's distance (scene units).
    pub znear: f64,
    /// `projection @ inverse(pose)` of the still camera.
    pub view_projection: Mat4,
}

/// (K+1,) segment boundaries from 0 to 1 for `objects` seen by `camera` (see the module).
/// `tolerance` in pixels, > 0. No objects: `[0, 1]`. Errors name `tolerance`, or `objects` for
/// a deforming motion whose vertex count is not its mesh's.
pub fn segment_times(
    objects: &[SegmentObject<'_>],
    camera: &SegmentCamera<'_>,
    tolerance: f64,
) -> Result<Vec<f64>> {
    if !(tolerance > 0.0) {
        return Err(Error::value(
            "tolerance",
            format!("must be > 0 pixels, got {tolerance}"),
        ));
    }
    if objects.is_empty() {
        return Ok(vec![0.0, 1.0]);
    }
    let mut rule = Rule::new(objects, camera, tolerance)?;
    let motions = objects
        .iter()
        .filter_map(|o| o.motion)
        .chain(camera.view.motion);
    let mut done: BTreeSet<u64> = [0.0f64, 1.0].iter().map(|t| t.to_bits()).collect();
    for m in motions {
        done.extend(
            m.times()
                .iter()
                .filter(|&&t| 0.0 < t && t < 1.0)
                .map(|t| t.to_bits()),
        );
    }
    // Times in [0, 1] order as their bits do.
    let cuts: Vec<f64> = done.iter().map(|&b| f64::from_bits(b)).collect();
    let mut heap = BinaryHeap::new();
    for w in cuts.windows(2) {
        rule.push(&mut heap, w[0], w[1])?;
    }
    while done.len() - 1 < MAX_SEGMENTS {
        let Some(Piece { a, b, .. }) = heap.pop() else {
            break;
        };
        let m = 0.5 * (a + b);
        done.insert(m.to_bits());
        rule.push(&mut heap, a, m)?;
        rule.push(&mut heap, m, b)?;
    }
    Ok(done.iter().map(|&b| f64::from_bits(b)).collect())
}

/// A piece over its tolerance by `off` (in tolerances); the heap pops the furthest first, then
/// the earliest (as a heap of `(-off, a, b)` tuples would).
#[derive(Clone, Copy, PartialEq)]
struct Piece {
    off: f64,
    a: f64,
    b: f64,
}

impl Eq for Piece {}

impl Ord for Piece {
    fn cmp(&self, other: &Self) -> Ordering {
        self.off
            .total_cmp(&other.off)
            .then(other.a.total_cmp(&self.a))
            .then(other.b.total_cmp(&self.b))
    }
}

impl PartialOrd for Piece {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// How one object gives its test points.
enum Points<'a> {
    /// A rigid (or still) object: the corners of its bounding box, placed by its motion.
    Corners([[f64; 3]; 8], Option<&'a Keyframes>),
    /// A deforming object: the positions of some of its vertices.
    Rows(&'a Keyframes, Vec<usize>),
}

/// The test vertices' normals of a deforming lambert object: the mesh of the faces touching
/// them (`local`, over the object's vertices `verts`), the test vertices' rows in it.
struct Probe<'a> {
    motion: &'a Keyframes,
    local: Mesh,
    verts: Vec<usize>,
    rows: Vec<usize>,
}

/// Clip-space positions of every test point at one time: (x, y, z) and w.
struct Clip {
    xyz: Vec<[f64; 3]>,
    w: Vec<f64>,
}

/// The rule's state: the test points and what has been measured at each time.
struct Rule<'a> {
    points: Vec<Points<'a>>,
    probes: Vec<Probe<'a>>,
    camera: SegmentCamera<'a>,
    tolerance: f64,
    clips: HashMap<u64, Clip>,
    normals: HashMap<u64, Vec<Vec<[f64; 3]>>>,
}

impl<'a> Rule<'a> {
    fn new(
        objects: &[SegmentObject<'a>],
        camera: &SegmentCamera<'a>,
        tolerance: f64,
    ) -> Result<Self> {
        let mut points = Vec::with_capacity(objects.len());
        let mut probes = Vec::new();
        for (i, o) in objects.iter().enumerate() {
            match o.motion {
                Some(k) if k.is_deforming() => {
                    let n = o.mesh.vertices().len();
                    if let Keys::Deforming { count, .. } = k.keys() {
                        if *count != n {
                            return Err(Error::shape(
                                "objects",
                                format!("object {i}: its motion moves {count} vertices, its mesh has {n}"),
                            ));
                        }
                    }
                    let rows = test_rows(n);
                    if let Some(p) = Probe::new(o, k, &rows)? {
                        probes.push(p);
                    }
                    points.push(Points::Rows(k, rows));
                }
                motion => points.push(Points::Corners(corners(o.mesh.vertices()), motion)),
            }
        }
        Ok(Rule {
            points,
            probes,
            camera: *camera,
            tolerance,
            clips: HashMap::new(),
            normals: HashMap::new(),
        })
    }

    /// Pushes `[a, b]` onto `heap` when it is longer than [`MIN_PIECE`] and over its tolerance.
    fn push(&mut self, heap: &mut BinaryHeap<Piece>, a: f64, b: f64) -> Result<()> {
        if b - a > MIN_PIECE {
            let off = self.off(a, b)?;
            if off > 1.0 {
                heap.push(Piece { off, a, b });
            }
        }
        Ok(())
    }

    /// How far `[a, b]` is from straight, in tolerances (> 1: halve it).
    fn off(&mut self, a: f64, b: f64) -> Result<f64> {
        let m = 0.5 * (a + b);
        for t in [a, b, m] {
            if !self.clips.contains_key(&t.to_bits()) {
                let c = self.clip(t);
                self.clips.insert(t.to_bits(), c);
            }
        }
        let [ca, cb, cm] = [a, b, m].map(|t| &self.clips[&t.to_bits()]);
        let worst = pixel_error(ca, cb, cm, &self.camera) / self.tolerance;
        let worst = if worst.is_nan() { f64::INFINITY } else { worst };
        if worst > 1.0 {
            return Ok(worst);
        }
        let bend = self.normals_off(a, b)?;
        Ok(if bend > worst { bend } else { worst })
    }

    /// The camera's view-projection at `t`.
    fn view_projection(&self, t: f64) -> Mat4 {
        let c = &self.camera;
        match c.view.motion {
            None => c.view_projection,
            Some(_) => c.view.view_projection_at(t),
        }
    }

    /// Clip-space positions of every test point at `t`.
    fn clip(&self, t: f64) -> Clip {
        let vp = self.view_projection(t);
        let (l, tr) = (linear_part(&vp), translation_part(&vp));
        let wrow = [vp[3][0], vp[3][1], vp[3][2]];
        let mut out = Clip {
            xyz: Vec::new(),
            w: Vec::new(),
        };
        let mut add = |p: [f64; 3]| {
            out.xyz.push(place(&l, &tr, &p));
            out.w.push(row_times(&p, &wrow) + vp[3][3]);
        };
        for pts in &self.points {
            match pts {
                Points::Corners(c, motion) => {
                    let m = motion.map_or(IDENTITY4, |k| k.transform_at(t));
                    let (ml, mt) = (linear_part(&m), translation_part(&m));
                    c.iter().for_each(|p| add(place(&ml, &mt, p)));
                }
                Points::Rows(k, rows) => k
                    .rows_at(t, rows)
                    .unwrap_or_default()
                    .into_iter()
                    .for_each(&mut add),
            }
        }
        out
    }

    /// The test vertices' unit normals at `t`, one list per probe.
    fn normals_at(&mut self, t: f64) -> Result<&Vec<Vec<[f64; 3]>>> {
        if !self.normals.contains_key(&t.to_bits()) {
            let n = self
                .probes
                .iter()
                .map(|p| p.normals(t))
                .collect::<Result<_>>()?;
            self.normals.insert(t.to_bits(), n);
        }
        Ok(&self.normals[&t.to_bits()])
    }

    /// The largest normal deviation at the middle of `[a, b]` over [`NORMAL_TOLERANCE`].
    fn normals_off(&mut self, a: f64, b: f64) -> Result<f64> {
        if self.probes.is_empty() {
            return Ok(0.0);
        }
        let m = 0.5 * (a + b);
        for t in [a, b, m] {
            self.normals_at(t)?;
        }
        let [na, nb, nm] = [a, b, m].map(|t| &self.normals[&t.to_bits()]);
        let mut worst = 0.0f64;
        for ((na, nb), nm) in na.iter().zip(nb).zip(nm) {
            if let Some(dev) = bend(na, nb, nm) {
                let d = dev / NORMAL_TOLERANCE;
                let d = if d.is_nan() { f64::INFINITY } else { d };
                worst = if d > worst { d } else { worst };
            }
        }
        Ok(worst)
    }
}

impl<'a> Probe<'a> {
    /// The probe of a deforming object's test vertices `rows`, or None for a flat-shaded
    /// object (or test vertices on no face).
    fn new(o: &SegmentObject<'_>, motion: &'a Keyframes, rows: &[usize]) -> Result<Option<Self>> {
        if !o.lambert {
            return Ok(None);
        }
        let mut tested = vec![false; o.mesh.vertices().len()];
        rows.iter().for_each(|&r| tested[r] = true);
        let sub: Vec<[u32; 3]> = o
            .mesh
            .faces()
            .iter()
            .filter(|f| f.iter().any(|&i| tested[i as usize]))
            .copied()
            .collect();
        if sub.is_empty() {
            return Ok(None);
        }
        let mut verts: Vec<usize> = sub.iter().flatten().map(|&i| i as usize).collect();
        verts.sort_unstable();
        verts.dedup();
        let find = |i: usize| verts.partition_point(|&v| v < i);
        let faces = sub
            .iter()
            .map(|f| f.map(|i| find(i as usize) as u32))
            .collect();
        // A test vertex on no face is measured at the next vertex that has one (numpy's
        // searchsorted did the same), none past the last.
        let local_rows = rows.iter().map(|&r| find(r)).filter(|&r| r < verts.len());
        let local_rows = local_rows.collect();
        let rest = verts.iter().map(|&v| o.mesh.vertices()[v]).collect();
        Ok(Some(Probe {
            motion,
            local: Mesh::new(rest, faces)?,
            verts,
            rows: local_rows,
        }))
    }

    /// The test vertices' unit normals at `t` (the mesh's vertex normals of the faces around
    /// them, placed at `t`).
    fn normals(&self, t: f64) -> Result<Vec<[f64; 3]>> {
        let n = self
            .local
            .with_vertices(self.motion.rows_at(t, &self.verts).unwrap_or_default())?
            .vertex_normals();
        Ok(self.rows.iter().map(|&r| n[r]).collect())
    }
}

/// `numpy.linspace(0, n - 1, min(n, DEFORMING_POINTS))` truncated to integers: the test
/// vertices of a deforming mesh of `n` vertices.
fn test_rows(n: usize) -> Vec<usize> {
    let k = n.min(DEFORMING_POINTS);
    if k <= 1 {
        return vec![0; k];
    }
    let step = (n - 1) as f64 / (k - 1) as f64;
    let mut rows: Vec<usize> = (0..k).map(|i| (i as f64 * step + 0.0) as usize).collect();
    rows[k - 1] = n - 1;
    rows
}

/// The corners of the bounding box of `v`, x slowest and z fastest.
fn corners(v: &[[f64; 3]]) -> [[f64; 3]; 8] {
    let (lo, hi) = v.iter().fold(
        ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
        |(lo, hi), p| {
            (
                std::array::from_fn(|k| lo[k].min(p[k])),
                std::array::from_fn(|k| hi[k].max(p[k])),
            )
        },
    );
    let pick = |bit: usize, k: usize| if bit == 0 { lo[k] } else { hi[k] };
    std::array::from_fn(|i| [pick(i >> 2 & 1, 0), pick(i >> 1 & 1, 1), pick(i & 1, 2)])
}

/// `clamp(q, -1, 1)`, NaN as 0: the image position a point's error is measured at.
fn on_image(q: f64) -> f64 {
    if q.is_nan() {
        0.0
    } else {
        q.clamp(-1.0, 1.0)
    }
}

/// The largest screen distance (pixels) between the test points at `m` and the middle of
/// their chords from `a` to `b`, as seen where it matters: per axis `|d_xy - p d_w| / w_l` (`d`
/// the difference, `p` the NDC position clamped to [-1, 1], `w_l` the chord's w, at least the
/// near plane's). NaN when any is NaN.
fn pixel_error(a: &Clip, b: &Clip, m: &Clip, camera: &SegmentCamera<'_>) -> f64 {
    let (half_w, half_h) = (
        0.5 * camera.view.width as f64,
        0.5 * camera.view.height as f64,
    );
    let mut worst = 0.0f64;
    for i in 0..m.w.len() {
        let (pa, pb, pm) = (a.xyz[i], b.xyz[i], m.xyz[i]);
        let wl = 0.5 * (a.w[i] + b.w[i]);
        let wm = m.w[i];
        let dx = 0.5 * (pa[0] + pb[0]) - pm[0];
        let dy = 0.5 * (pa[1] + pb[1]) - pm[1];
        let dw = wl - wm;
        let (px, py) = (on_image(pm[0] / wm), on_image(pm[1] / wm));
        let wl = if wl.is_nan() {
            wl
        } else {
            wl.max(camera.znear)
        };
        let ex = (dx - px * dw).abs() / wl * half_w;
        let ey = (dy - py * dw).abs() / wl * half_h;
        let e = ex.hypot(ey);
        if e.is_nan() {
            return e;
        }
        worst = worst.max(e);
    }
    worst
}

/// `sqrt((x0 x0 + x1 x1) + x2 x2)`, as numpy's `linalg.norm` of a row.
fn length(x: [f64; 3]) -> f64 {
    (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt()
}

/// The largest distance between a unit normal of `nm` and the direction of the sum of its
/// normals in `na` and `nb`, over the vertices whose sum and middle normal are not zero (None
/// when there is none). NaN when any distance is NaN.
fn bend(na: &[[f64; 3]], nb: &[[f64; 3]], nm: &[[f64; 3]]) -> Option<f64> {
    let mut worst: Option<f64> = None;
    for ((a, b), m) in na.iter().zip(nb).zip(nm) {
        let mean: [f64; 3] = std::array::from_fn(|k| a[k] + b[k]);
        let len = length(mean);
        if !(len > 1e-12 && length(*m) > 0.0) {
            continue;
        }
        let d = length(std::array::from_fn(|k| m[k] - mean[k] / len));
        worst = Some(match worst {
            Some(w) if w.is_nan() || !(d > w) && !d.is_nan() => w,
            _ => d,
        });
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{grid_faces, uv_sphere};
    use crate::motion::axis_angle;
    use crate::motion::mat4_mul;
    use crate::raster::Camera;
    use glam::DMat4;

    fn shift(x: f64, z: f64) -> Mat4 {
        let mut m = IDENTITY4;
        m[0][3] = x;
        m[2][3] = z;
        m
    }

    /// A camera at the origin looking down -z, 64 x 48 pixels.
    fn camera() -> SegmentCamera<'static> {
        let cam = Camera::new(
            DMat4::IDENTITY,
            std::f64::consts::FRAC_PI_3,
            64,
            48,
            0.05,
            f64::INFINITY,
        )
        .unwrap();
        let rows = |m: DMat4| m.transpose().to_cols_array_2d();
        SegmentCamera {
            view: MovingCamera {
                width: 64,
                height: 48,
                projection: rows(cam.projection),
                pose: IDENTITY4,
                motion: None,
            },
            znear: 0.05,
            view_projection: rows(cam.projection * cam.view),
        }
    }

    fn cube() -> Mesh {
        let (v, f) = uv_sphere(4, 8);
        Mesh::new(v, f).unwrap()
    }

    #[test]
    fn a_straight_translation_needs_one_segment() {
        let mesh = cube();
        let k = Keyframes::rigid(vec![0.0, 1.0], &[shift(-1.0, -5.0), shift(1.0, -4.0)], "m");
        let k = k.unwrap();
        let o = SegmentObject {
            mesh: &mesh,
            motion: Some(&k),
            lambert: true,
        };
        assert_eq!(segment_times(&[o], &camera(), 0.01).unwrap(), [0.0, 1.0]);
        assert_eq!(segment_times(&[], &camera(), 0.01).unwrap(), [0.0, 1.0]);
        assert!(segment_times(&[o], &camera(), 0.0).is_err());
    }

    #[test]
    fn a_turn_needs_more_and_no_piece_is_shorter_than_min_piece() {
        let mesh = cube();
        let turn = |a: f64| mat4_mul(&shift(0.0, -5.0), &axis_angle(a, [0.0, 1.0, 0.0], [0.0; 3]));
        let k = Keyframes::rigid(vec![0.0, 0.5, 1.0], &[turn(0.0), turn(1.0), turn(2.0)], "m");
        let k = k.unwrap();
        let o = SegmentObject {
            mesh: &mesh,
            motion: Some(&k),
            lambert: false,
        };
        let coarse = segment_times(&[o], &camera(), 1.0).unwrap();
        let fine = segment_times(&[o], &camera(), 0.01).unwrap();
        assert!(coarse.len() > 3 && fine.len() > coarse.len() && fine.len() <= MAX_SEGMENTS + 1);
        assert!(fine.contains(&0.5), "cut at the keyframe");
        let tiny = segment_times(&[o], &camera(), 1e-12).unwrap();
        assert_eq!(tiny.len(), MAX_SEGMENTS + 1);
        for t in [&coarse, &fine, &tiny] {
            assert_eq!((t[0], t[t.len() - 1]), (0.0, 1.0));
            assert!(t.windows(2).all(|w| w[1] - w[0] >= MIN_PIECE / 2.0));
        }
    }

    #[test]
    fn a_bending_lambert_sheet_is_cut_for_its_normals_only() {
        // A flat 3 x 3 grid folding about its middle column: its vertices move on straight
        // lines (vertex keyframes), its normals turn.
        let flat: Vec<[f64; 3]> = (0..9)
            .map(|i| [(i % 3) as f64 - 1.0, (i / 3) as f64 - 1.0, -5.0])
            .collect();
        let folded: Vec<[f64; 3]> = flat
            .iter()
            .map(|p| [p[0], p[1], p[2] + p[0].abs()])
            .collect();
        let mesh = Mesh::new(flat.clone(), grid_faces(2)).unwrap();
        let k = Keyframes::deforming(vec![0.0, 1.0], [flat, folded].concat()).unwrap();
        let mut o = SegmentObject {
            mesh: &mesh,
            motion: Some(&k),
            lambert: false,
        };
        assert_eq!(segment_times(&[o], &camera(), 0.01).unwrap(), [0.0, 1.0]);
        o.lambert = true;
        assert!(segment_times(&[o], &camera(), 0.01).unwrap().len() > 2);
        let small = Mesh::new(vec![[0.0; 3]; 3], vec![[0, 1, 2]]).unwrap();
        o.mesh = &small;
        let err = segment_times(&[o], &camera(), 0.01)
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("objects: object 0"), "{err}");
    }

    #[test]
    fn rows_and_test_rows_match_the_engine_and_linspace() {
        assert_eq!(test_rows(1), [0]);
        assert_eq!(test_rows(3), [0, 1, 2]);
        let r = test_rows(1000);
        assert_eq!((r.len(), r[0], r[1], r[255]), (256, 0, 3, 999));
        let v: Vec<[f64; 3]> = (0..6).map(|i| [i as f64, 0.1 * i as f64, 1.0]).collect();
        let k = Keyframes::deforming(vec![0.2, 0.7], v).unwrap();
        for t in [0.0, 0.3, 0.45, 0.7, 1.0] {
            let all = k.vertices_at(t).unwrap();
            assert_eq!(k.rows_at(t, &[0, 2]).unwrap(), [all[0], all[2]]);
        }
    }
}
