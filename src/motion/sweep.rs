//! The screen sweep: a forecast of accumulation's error from the scene's geometry alone
//! ([`sweep`]'s `scale`), read by the planner (`auto`) to choose its first render's samples. The
//! render's own halves certify the frame; this only picks where to start.
//!
//! With one sample a pixel, a pixel an outline passes over changes its colour once during the
//! shutter, and N stratified time samples place that step to within half a stratum (an error
//! of about the contrast over N sqrt 12). The pixels that step are about those an object's
//! outline sweeps: its screen perimeter times the distance its surface travels on screen. So
//!
//! ```text
//! sweep_scale^2 = sum over objects of perimeter x path x contrast^2 / pixels
//! ```
//!
//! `perimeter`: twice the sum of the sides (pixels, clipped to the image) of the bounding box at
//! mid-shutter of the object's [`SWEEP_POINTS`] surface points seen at some time, plus one;
//! `path`: their mean screen path over [`SWEEP_TIMES`] evenly spaced shutter times (pixels;
//! a step with either end behind the eye counts 0); `contrast^2`: the mean over RGBA of the
//! squared difference the object's premultiplied colour at [`SWEEP_SHADE`] makes over the
//! background (with a colour a vertex, the mean over the vertices too).
use crate::mesh::Mesh;
use crate::motion::{linear_part, place, translation_part, Keyframes, Keys, Mat4, MovingCamera};

/// Shutter times the surface points are followed at (evenly spaced, both ends included).
pub const SWEEP_TIMES: usize = 5;
/// Surface points followed per object (at most four a face).
pub const SWEEP_POINTS: usize = 64;
/// The shading factor of an object's colour in its contrast (a typical lambert shade).
pub const SWEEP_SHADE: f64 = 0.6;

/// One object of the forecast: its mesh (object space, or a deforming motion's rest pose), its
/// motion (None: still) and its straight RGBA colour or colours.
#[derive(Clone, Copy)]
pub struct SweepObject<'a> {
    /// The object's mesh.
    pub mesh: &'a Mesh,
    /// Rigid or deforming keyframes, or None.
    pub motion: Option<&'a Keyframes>,
    /// Straight RGBA: one colour, or one a vertex (the contrast is their mean, each vertex
    /// standing for as much of the surface).
    pub rgba: &'a [[f64; 4]],
}

/// The screen sweep of a scene and where it comes from ([`sweep`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sweep {
    /// `sweep_scale` of the module docs: 0 when no object is seen.
    pub scale: f64,
    /// The objects' mean screen paths (pixels), each weighted by its share of `scale^2`
    /// (perimeter x path x contrast^2): the path of the outlines the error comes from; 0 when
    /// no object adds to the sweep.
    pub path: f64,
}

/// The scene's screen sweep and the path its outlines travel ([`Sweep`]; see the module).
/// `background` is straight RGBA. The objects are those that move on screen (all of them under
/// camera motion).
pub fn sweep(
    objects: &[SweepObject<'_>],
    camera: &MovingCamera<'_>,
    background: [f64; 4],
) -> Sweep {
    let times: [f64; SWEEP_TIMES] = std::array::from_fn(|k| k as f64 / (SWEEP_TIMES - 1) as f64);
    let views: Vec<Mat4> = times
        .iter()
        .map(|&t| camera.view_projection_at(t))
        .collect();
    let size = [f64::from(camera.width), f64::from(camera.height)];
    let under = [
        background[0] * background[3],
        background[1] * background[3],
        background[2] * background[3],
        background[3],
    ];
    let (mut total, mut paths) = (0.0, 0.0);
    for o in objects {
        let track = Track::follow(o, &times, &views, size);
        let share = track.perimeter * track.path * mean_contrast2(o.rgba, under);
        total += share;
        paths += share * track.path;
    }
    Sweep {
        scale: (total / (size[0] * size[1])).sqrt(),
        path: if total > 0.0 { paths / total } else { 0.0 },
    }
}

/// One object's surface points followed on screen: their mean path and their perimeter
/// (both 0 when none is seen).
struct Track {
    path: f64,
    perimeter: f64,
}

impl Track {
    fn follow(o: &SweepObject<'_>, times: &[f64], views: &[Mat4], size: [f64; 2]) -> Self {
        let points = surface_points(o.mesh);
        let (mut path, mut seen_count) = (0.0, 0usize);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        let mid = times.len() / 2;
        let nothing = Self {
            path: 0.0,
            perimeter: 0.0,
        };
        let mut screens: Vec<Vec<Option<[f64; 2]>>> = Vec::with_capacity(times.len());
        for (&t, vp) in times.iter().zip(views) {
            let Some(world) = world_at(o, &points, t) else {
                return nothing; // a deforming motion of another vertex count: nothing known
            };
            screens.push(world.iter().map(|p| screen(vp, p, size)).collect());
        }
        for i in 0..points.len() {
            let seen = screens
                .iter()
                .any(|s| s[i].is_some_and(|q| inside(q, size)));
            if !seen {
                continue;
            }
            seen_count += 1;
            path += screens
                .windows(2)
                .map(|w| match (w[0][i], w[1][i]) {
                    (Some(a), Some(b)) => (a[0] - b[0]).hypot(a[1] - b[1]),
                    _ => 0.0,
                })
                .sum::<f64>();
            if let Some(q) = screens[mid][i] {
                for k in 0..2 {
                    let c = q[k].clamp(0.0, size[k]);
                    lo[k] = lo[k].min(c);
                    hi[k] = hi[k].max(c);
                }
            }
        }
        if seen_count == 0 {
            return nothing;
        }
        let extent: f64 = (0..2)
            .map(|k| if hi[k] >= lo[k] { hi[k] - lo[k] } else { 0.0 })
            .sum();
        Self {
            path: path / seen_count as f64,
            perimeter: 2.0 * extent + 1.0,
        }
    }
}

/// The surface points of a mesh: up to [`SWEEP_POINTS`] (four a face at most), point `m` on
/// face `m F / M` at a low-discrepancy barycentric position; as (face, barycentric weights).
fn surface_points(mesh: &Mesh) -> Vec<(usize, [f64; 3])> {
    let faces = mesh.faces().len();
    let count = SWEEP_POINTS.min(4 * faces);
    (0..count)
        .map(|m| {
            let x = m as f64;
            let (mut u, mut v) = (
                (x * 0.618_033_988_749_894_9) % 1.0,
                (x * 0.754_877_666_246_692_7 + 0.5) % 1.0,
            );
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            (m * faces / count, [1.0 - u - v, u, v])
        })
        .collect()
}

/// The world positions at `t` of the surface points: placed by a rigid motion, or on the
/// positions at `t` of their faces' corners under a deforming one (only those rows, not the
/// whole mesh); None when a deforming motion's vertex count is not the mesh's.
fn world_at(o: &SweepObject<'_>, points: &[(usize, [f64; 3])], t: f64) -> Option<Vec<[f64; 3]>> {
    let faces = o.mesh.faces();
    let on = |[a, b, c]: [[f64; 3]; 3], w: [f64; 3]| -> [f64; 3] {
        std::array::from_fn(|k| w[0] * a[k] + w[1] * b[k] + w[2] * c[k])
    };
    if let Some(k) = o.motion.filter(|k| k.is_deforming()) {
        if !matches!(k.keys(), Keys::Deforming { count, .. } if *count == o.mesh.vertices().len()) {
            return None;
        }
        let rows: Vec<usize> = points
            .iter()
            .flat_map(|&(f, _)| faces[f].map(|i| i as usize))
            .collect();
        let at = k.rows_at(t, &rows)?;
        return Some(
            points
                .iter()
                .zip(at.chunks_exact(3))
                .map(|(&(_, w), c)| on([c[0], c[1], c[2]], w))
                .collect(),
        );
    }
    let verts = o.mesh.vertices();
    let rest = points
        .iter()
        .map(|&(f, w)| on(faces[f].map(|i| verts[i as usize]), w));
    Some(match o.motion.map(|k| k.transform_at(t)) {
        Some(m) => {
            let (l, tr) = (linear_part(&m), translation_part(&m));
            rest.map(|p| place(&l, &tr, &p)).collect()
        }
        None => rest.collect(),
    })
}

/// The image position of world point `p` under view-projection `vp` (None behind the eye).
fn screen(vp: &Mat4, p: &[f64; 3], size: [f64; 2]) -> Option<[f64; 2]> {
    let row = |r: usize| vp[r][0] * p[0] + vp[r][1] * p[1] + vp[r][2] * p[2] + vp[r][3];
    let w = row(3);
    (w > 1e-9).then(|| {
        [
            (row(0) / w * 0.5 + 0.5) * size[0],
            (-row(1) / w * 0.5 + 0.5) * size[1],
        ]
    })
}

fn inside(q: [f64; 2], size: [f64; 2]) -> bool {
    (0.0..=size[0]).contains(&q[0]) && (0.0..=size[1]).contains(&q[1])
}

/// [`contrast2`] of each colour of `rgba`, their mean (0 for none).
fn mean_contrast2(rgba: &[[f64; 4]], under: [f64; 4]) -> f64 {
    if rgba.is_empty() {
        return 0.0;
    }
    rgba.iter().map(|&c| contrast2(c, under)).sum::<f64>() / rgba.len() as f64
}

/// The mean over RGBA of the squared difference straight `rgba` at [`SWEEP_SHADE`] makes over
/// premultiplied `under`.
fn contrast2(rgba: [f64; 4], under: [f64; 4]) -> f64 {
    let a = rgba[3];
    let d = [
        (rgba[0] * SWEEP_SHADE - under[0]) * a,
        (rgba[1] * SWEEP_SHADE - under[1]) * a,
        (rgba[2] * SWEEP_SHADE - under[2]) * a,
        (1.0 - under[3]) * a,
    ];
    d.iter().map(|x| x * x).sum::<f64>() / 4.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::Similarity;

    fn shift(x: f64, z: f64) -> Mat4 {
        Similarity::translate([x, 0.0, z]).matrix
    }

    fn square() -> Mesh {
        let v = vec![
            [-0.5, -0.5, 0.0],
            [0.5, -0.5, 0.0],
            [0.5, 0.5, 0.0],
            [-0.5, 0.5, 0.0],
        ];
        Mesh::new(v, vec![[0, 1, 2], [0, 2, 3]]).unwrap()
    }

    /// A 90-degree camera 5 units back looking down -z at a `w` x `w` image.
    fn camera(w: u32) -> MovingCamera<'static> {
        let (n, f) = (0.1, 100.0);
        let mut p = [[0.0; 4]; 4];
        p[0][0] = 1.0;
        p[1][1] = 1.0;
        p[2][2] = (f + n) / (n - f);
        p[2][3] = 2.0 * f * n / (n - f);
        p[3][2] = -1.0;
        MovingCamera {
            width: w,
            height: w,
            projection: p,
            pose: shift(0.0, 5.0),
            motion: None,
        }
    }

    /// The sweep of the square moved from `from` to `to` (x, z) in a `w` x `w` image.
    fn sweep_of(
        from: (f64, f64),
        to: (f64, f64),
        w: u32,
        rgba: [f64; 4],
        background: [f64; 4],
    ) -> f64 {
        let mesh = square();
        let keys = Keyframes::rigid(
            vec![0.0, 1.0],
            &[shift(from.0, from.1), shift(to.0, to.1)],
            "m",
        )
        .unwrap();
        let o = SweepObject {
            mesh: &mesh,
            motion: Some(&keys),
            rgba: &[rgba],
        };
        sweep(&[o], &camera(w), background).scale
    }

    fn scale(moves: f64, rgba: [f64; 4], background: [f64; 4]) -> f64 {
        sweep_of((0.0, 0.0), (moves, 0.0), 100, rgba, background)
    }

    #[test]
    fn the_scale_grows_as_the_square_root_of_the_path_and_is_zero_for_no_contrast() {
        let white = [1.0, 1.0, 1.0, 1.0];
        let clear = [0.0; 4];
        let (a, b) = (scale(0.5, white, clear), scale(2.0, white, clear));
        // a unit square at distance 5 under a 90-degree view of 100 px: 10 px a unit
        assert!((b / a - 2.0).abs() < 1e-9, "{a} {b}");
        // every point moves 5 px; the points lie inside the 10 x 10 px square, most of its extent
        let most = ((2.0 * 20.0 + 1.0) * 5.0 * contrast2(white, clear) / 1e4).sqrt();
        assert!(a <= most && a > 0.9 * most, "{a} {most}");
        // the same colour as an opaque background: nothing to see
        let grey = [0.6, 0.6, 0.6, 1.0];
        assert_eq!(scale(2.0, [1.0, 1.0, 1.0, 1.0], grey), 0.0);
    }

    #[test]
    fn an_object_out_of_view_or_behind_the_eye_adds_nothing() {
        let (white, clear) = ([1.0; 4], [0.0; 4]);
        assert_eq!(sweep_of((50.0, 0.0), (51.0, 0.0), 64, white, clear), 0.0);
        assert_eq!(sweep_of((0.0, 9.0), (1.0, 9.0), 64, white, clear), 0.0);
        assert_eq!(sweep(&[], &camera(64), clear).scale, 0.0);
    }

    #[test]
    fn a_deforming_motion_of_another_vertex_count_adds_nothing() {
        let mesh = square();
        let keys = Keyframes::deforming(vec![0.0, 1.0], vec![[0.0; 3]; 6]).unwrap();
        let o = SweepObject {
            mesh: &mesh,
            motion: Some(&keys),
            rgba: &[[1.0; 4]],
        };
        assert_eq!(sweep(&[o], &camera(64), [0.0; 4]).scale, 0.0);
    }

    #[test]
    fn the_path_is_the_screen_distance_of_the_objects_that_add_to_the_sweep() {
        let mesh = square();
        let rigid = |dx: f64| {
            Keyframes::rigid(vec![0.0, 1.0], &[shift(0.0, 0.0), shift(dx, 0.0)], "m").unwrap()
        };
        let (near, far) = (rigid(0.5), rigid(2.0));
        let (white, clear): (&[[f64; 4]], _) = (&[[1.0; 4]], [0.0; 4]);
        let object = |keys, rgba| SweepObject {
            mesh: &mesh,
            motion: Some(keys),
            rgba,
        };
        // 10 px a unit (above): every point travels 5 px, and 20 px
        let one = sweep(&[object(&near, white)], &camera(100), clear);
        assert!((one.path - 5.0).abs() < 1e-6, "{one:?}");
        // the same object's scale as `scale` reads it (one call gives both)
        assert_eq!(one.scale, scale(0.5, [1.0; 4], clear));
        // an object of the background's colour adds nothing, whatever it travels
        let unseen: &[[f64; 4]] = &[[0.0; 4]];
        let two = sweep(
            &[object(&near, white), object(&far, unseen)],
            &camera(100),
            clear,
        );
        assert!((two.path - 5.0).abs() < 1e-6, "{two:?}");
        // two seen: weighted by perimeter x path x contrast^2, the longer path weighs 4x
        let both = sweep(
            &[object(&near, white), object(&far, white)],
            &camera(100),
            clear,
        );
        assert!(
            (both.path - (5.0 + 4.0 * 20.0) / 5.0).abs() < 1e-6,
            "{both:?}"
        );
        assert_eq!(sweep(&[], &camera(64), clear).path, 0.0);
    }

    #[test]
    fn per_vertex_colours_weigh_their_mean_contrast() {
        let (white, clear) = ([1.0; 4], [0.0; 4]);
        let half = [0.5, 0.5, 0.5, 1.0];
        let mesh = square();
        let keys =
            Keyframes::rigid(vec![0.0, 1.0], &[shift(0.0, 0.0), shift(1.0, 0.0)], "m").unwrap();
        let of = |rgba: &[[f64; 4]]| {
            let o = SweepObject {
                mesh: &mesh,
                motion: Some(&keys),
                rgba,
            };
            sweep(&[o], &camera(100), clear).scale
        };
        let mixed = of(&[white, white, half, half]);
        let mean = 0.5 * (contrast2(white, clear) + contrast2(half, clear));
        let expected = of(&[white]) * (mean / contrast2(white, clear)).sqrt();
        assert!(
            (mixed - expected).abs() < 1e-12 * expected,
            "{mixed} {expected}"
        );
        assert_eq!(of(&[]), 0.0);
    }
}
