//! Exact oracles for the analytic method: a square translating parallel to the image plane
//! covers each sample for a closed-form interval of time.
use glam::{DMat4, DVec3};

use super::*;
use crate::analytic::{resolve, visibility};
use crate::frame::Frame;
use crate::raster::Shading;
use crate::shutter::Shutter;

const W: u32 = 48;
const H: u32 = 36;
const YFOV: f64 = 0.8;
const DIST: f64 = 5.0;

fn camera() -> DMat4 {
    let view = DMat4::look_at_rh(DVec3::new(0.0, 0.0, DIST), DVec3::ZERO, DVec3::Y);
    DMat4::perspective_rh_gl(YFOV, f64::from(W) / f64::from(H), 0.5, 50.0) * view
}

/// A square of half-size `h` in the plane z = 0 as an `n` x `n` grid of quads (two triangles
/// each), at boundary positions shifted by `dx[k]` along x.
fn grid_square(h: f64, n: usize, dx: &[f64]) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let mut base = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let u = -h + 2.0 * h * i as f64 / n as f64;
            let v = -h + 2.0 * h * j as f64 / n as f64;
            base.push([u, v, 0.0]);
        }
    }
    let mut faces = Vec::new();
    let row = (n + 1) as u32;
    for j in 0..n as u32 {
        for i in 0..n as u32 {
            let a = j * row + i;
            faces.push([a, a + 1, a + row + 1]);
            faces.push([a, a + row + 1, a + row]);
        }
    }
    let pos = dx
        .iter()
        .flat_map(|d| base.iter().map(move |p| [p[0] + d, p[1], p[2]]))
        .collect();
    (pos, faces)
}

/// The world point on z = 0 seen at the centre of sample (ix, iy).
fn on_plane(ix: u32, iy: u32) -> (f64, f64) {
    let t = (YFOV / 2.0).tan() * DIST;
    let xn = 2.0 * (f64::from(ix) + 0.5) / f64::from(W) - 1.0;
    let yn = 1.0 - 2.0 * (f64::from(iy) + 0.5) / f64::from(H);
    (xn * t * f64::from(W) / f64::from(H), yn * t)
}

fn render_square(
    pos: &[[f64; 3]],
    faces: &[[u32; 3]],
    times: &[f64],
    shutter: &Shutter,
) -> (Frame, Stats) {
    render_within(pos, faces, times, shutter, DEFAULT_TILE_BUDGET).unwrap()
}

fn render_within(
    pos: &[[f64; 3]],
    faces: &[[u32; 3]],
    times: &[f64],
    shutter: &Shutter,
    tile_budget: usize,
) -> crate::Result<(Frame, Stats)> {
    let vp = [camera()];
    let rgba = [[1.0f32, 1.0, 1.0, 1.0]];
    let draws = [MovingDraw {
        positions: pos,
        faces,
        rgba: &rgba,
        normals: None,
        object_id: 7,
        cull_back: true,
        shading: Shading::Flat,
    }];
    render(&Input {
        width: W,
        height: H,
        samples: 1,
        times,
        view_projections: &vp,
        draws: &draws,
        backdrop: None,
        shutter,
        lights: &[],
        ambient: [0.0; 3],
        quadrature: Quadrature::Auto,
        reference_time: 1.0,
        shade: true,
        tile_budget,
        exposure: None,
        rolling: Default::default(),
    })
}

fn check_square(n: usize, shutter: Shutter) {
    let (h, x0, x1) = (0.6, -1.5, 1.2);
    let (pos, faces) = grid_square(h, n, &[x0, x1]);
    let (f, _) = render_square(&pos, &faces, &[0.0, 1.0], &shutter);
    let mut worst: f64 = 0.0;
    for iy in 0..H {
        for ix in 0..W {
            let (x, y) = on_plane(ix, iy);
            // the square covers x while x0 + t (x1 - x0) is within h of x
            let want = if y.abs() <= h {
                let a = ((x - h - x0) / (x1 - x0)).clamp(0.0, 1.0);
                let b = ((x + h - x0) / (x1 - x0)).clamp(0.0, 1.0);
                shutter.cumulative(b) - shutter.cumulative(a)
            } else {
                0.0
            };
            let got = f64::from(f.rgba[4 * (iy * W + ix) as usize + 3]);
            worst = worst.max((got - want).abs());
        }
    }
    assert!(
        worst < 1e-5,
        "{shutter:?}, {n}x{n} grid: worst coverage error {worst}"
    );
}

#[test]
fn translating_square_covers_each_sample_for_the_closed_form_time() {
    check_square(1, Shutter::Box);
    check_square(1, Shutter::Triangle);
}

#[test]
fn a_square_made_of_many_triangles_has_no_seams() {
    check_square(7, Shutter::Box);
    check_square(
        7,
        Shutter::Weights {
            cum: vec![0.0, 0.1, 0.1, 0.6, 1.0],
        },
    );
}

#[test]
fn segments_of_a_linear_motion_change_nothing_but_rounding() {
    let (pos1, faces) = grid_square(0.6, 3, &[-1.5, 1.2]);
    let xs: Vec<f64> = (0..=4).map(|k| -1.5 + 2.7 * k as f64 / 4.0).collect();
    let (pos4, _) = grid_square(0.6, 3, &xs);
    let (a, _) = render_square(&pos1, &faces, &[0.0, 1.0], &Shutter::Box);
    let (b, _) = render_square(&pos4, &faces, &[0.0, 0.25, 0.5, 0.75, 1.0], &Shutter::Box);
    let worst = a
        .rgba
        .iter()
        .zip(&b.rgba)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-5, "{worst}");
}

#[test]
fn the_result_does_not_depend_on_the_thread_count() {
    let (pos, faces) = grid_square(0.6, 9, &[-1.5, 1.2]);
    let one = crate::on_threads(1, || {
        render_square(&pos, &faces, &[0.0, 1.0], &Shutter::Gaussian).0
    });
    let two = crate::on_threads(3, || {
        render_square(&pos, &faces, &[0.0, 1.0], &Shutter::Gaussian).0
    });
    assert_eq!(one.rgba, two.rgba);
    assert_eq!(one.depth, two.depth);
    assert_eq!(one.ids, two.ids);
    assert_eq!(one.velocity, two.velocity);
}

#[test]
fn a_small_memory_budget_splits_tiles_and_changes_no_bit() {
    // a 9x9 grid with three segments: chains of many links at every covered sample
    let xs = [-1.5, -0.4, 0.3, 1.2];
    let (pos, faces) = grid_square(0.6, 9, &xs);
    let times = [0.0, 0.3, 0.7, 1.0];
    let (whole, whole_stats) = render_square(&pos, &faces, &times, &Shutter::Triangle);
    assert_eq!(whole_stats.splits, 0);
    let mut splits = Vec::new();
    for budget in [200_000, 40_000, 12_000] {
        let (f, stats) = render_within(&pos, &faces, &times, &Shutter::Triangle, budget).unwrap();
        assert_eq!(f.rgba, whole.rgba, "budget {budget}");
        assert_eq!(f.depth, whole.depth);
        assert_eq!(f.ids, whole.ids);
        assert_eq!(f.velocity, whole.velocity);
        assert_eq!(
            (stats.intervals, stats.spans, stats.pieces),
            (whole_stats.intervals, whole_stats.spans, whole_stats.pieces)
        );
        splits.push(stats.splits);
    }
    // a smaller budget splits more, down to rows and single samples
    assert!(
        splits[0] > 0 && splits[0] < splits[1] && splits[1] < splits[2],
        "{splits:?}"
    );
    // a budget no single sample fits in fails with a memory error naming the draws and the
    // setting to raise
    match render_within(&pos, &faces, &times, &Shutter::Triangle, 64) {
        Err(e @ crate::Error::Memory { .. }) => {
            let msg = e.to_string();
            assert!(msg.starts_with("draws:"), "{msg}");
            assert!(msg.contains("TILE_BUDGET_BYTES"), "{msg}");
        }
        other => panic!("expected a memory error, got {:?}", other.map(|f| f.1)),
    }
}

#[test]
fn depth_ids_and_velocity_describe_the_surface_at_the_reference_time() {
    let (pos, faces) = grid_square(0.6, 1, &[-1.5, 1.2]);
    let (f, _) = render_square(&pos, &faces, &[0.0, 1.0], &Shutter::Box);
    let velocity = f.velocity.expect("the analytic frame writes velocity");
    // at the close the square is centred at x = 1.2
    let (ix, iy) = (W / 2 + 9, H / 2);
    let (x, _) = on_plane(ix, iy);
    assert!((x - 1.2).abs() < 0.6);
    let i = (iy * W + ix) as usize;
    assert_eq!(f.ids[i], 7);
    assert!((f.depth[i] - DIST as f32).abs() < 1e-4, "{}", f.depth[i]);
    // 2.7 world units at distance 5 with this field of view, in pixels
    let px = 2.7 / ((YFOV / 2.0).tan() * DIST) * f64::from(H) / 2.0;
    assert!((f64::from(velocity[2 * i]) - px).abs() < 1e-3);
    assert!(velocity[2 * i + 1].abs() < 1e-4);
    let far = 0; // the top-left pixel never sees it
    assert_eq!((f.ids[far], f.depth[far]), (-1, f32::INFINITY));
}

#[test]
fn bad_input_names_the_argument() {
    let (pos, faces) = grid_square(0.6, 1, &[-1.5, 1.2]);
    let vp = [camera()];
    let rgba = [[1.0f32; 4]];
    let draw = MovingDraw {
        positions: &pos,
        faces: &faces,
        rgba: &rgba,
        normals: None,
        object_id: 0,
        cull_back: true,
        shading: Shading::Flat,
    };
    let good = Input {
        width: W,
        height: H,
        samples: 1,
        times: &[0.0, 1.0],
        view_projections: &vp,
        draws: std::slice::from_ref(&draw),
        backdrop: None,
        shutter: &Shutter::Box,
        lights: &[],
        ambient: [0.0; 3],
        quadrature: Quadrature::Auto,
        reference_time: 1.0,
        shade: true,
        tile_budget: DEFAULT_TILE_BUDGET,
        rolling: Default::default(),
        exposure: None,
    };
    assert!(render(&good).is_ok());
    let err = |i: Input| render(&i).unwrap_err().to_string();
    assert!(err(Input {
        times: &[0.0, 0.5],
        ..good.clone()
    })
    .starts_with("times"));
    assert!(err(Input {
        times: &[0.0, 0.5, 0.5, 1.0],
        ..good.clone()
    })
    .starts_with("times"));
    assert!(err(Input {
        reference_time: 1.5,
        ..good.clone()
    })
    .starts_with("reference_time"));
    let bad_faces = [[0u32, 1, 99]];
    let d2 = MovingDraw {
        faces: &bad_faces,
        ..draw
    };
    assert!(err(Input {
        draws: std::slice::from_ref(&d2),
        ..good.clone()
    })
    .starts_with("faces"));
    let nan = vec![[f64::NAN; 3]; pos.len()];
    let d3 = MovingDraw {
        positions: &nan,
        ..draw
    };
    assert!(err(Input {
        draws: std::slice::from_ref(&d3),
        ..good.clone()
    })
    .starts_with("positions"));
}

/// Layers of flat colours, reporting them as uniform or not.
struct FlatLayers {
    colors: Vec<[f32; 4]>,
    uniform: bool,
    links: Vec<visibility::Link>,
}

impl resolve::Layers for FlatLayers {
    fn opaque(&self, f: &visibility::Frag) -> bool {
        self.colors[f.prim as usize][3] >= 1.0
    }
    fn uniform(&self, f: &visibility::Frag) -> Option<[f32; 4]> {
        let c = self.colors[f.prim as usize];
        self.uniform
            .then_some([c[0] * c[3], c[1] * c[3], c[2] * c[3], c[3]])
    }
    fn cuts(&mut self, _i: usize, f: &visibility::Frag, a: f64, b: f64, out: &mut Vec<f64>) {
        let mut c = self.links[f.chain as usize].next;
        while c != visibility::NONE {
            let t = f64::from(self.links[c as usize].t0);
            if t > a && t < b {
                out.push(t);
            }
            c = self.links[c as usize].next;
        }
    }
    fn triangle(&mut self, _i: usize, f: &visibility::Frag, _t: f64) -> (u32, f64) {
        (f.prim, f64::INFINITY)
    }
    fn kinks(&mut self, _p: u32, _a: f64, _b: f64, _out: &mut Vec<f64>) {}
    fn bend(&self, _p: u32) -> f32 {
        0.0
    }
    fn shade(&mut self, p: u32, _t: f64) -> [f32; 4] {
        let c = self.colors[p as usize];
        [c[0] * c[3], c[1] * c[3], c[2] * c[3], c[3]]
    }
}

#[test]
fn uniform_layers_resolve_as_their_shading_does() {
    let colors = vec![
        [0.9, 0.2, 0.1, 1.0],
        [0.1, 0.8, 0.3, 0.5],
        [0.2, 0.3, 0.9, 0.25],
        [0.6, 0.6, 0.1, 1.0],
    ];
    // fragment k's chain starts at link k; fragment 0 has a second link (a chain of one
    // colour: the uniform composite holds across its links too)
    let link = |t0: f32, z0: f32, prim: u32, next: u32| visibility::Link { t0, z0, prim, next };
    let links = vec![
        link(0.0, 1.0, 0, 4),
        link(0.1, 2.5, 1, visibility::NONE),
        link(0.3, 2.0, 2, visibility::NONE),
        link(0.55, 0.5, 3, visibility::NONE),
        link(0.4, 3.5, 0, visibility::NONE),
    ];
    let frag = |t0: f32, t1: f32, z0: f32, z1: f32, prim: u32| visibility::Frag {
        t0,
        t1,
        z0,
        z1,
        prim,
        chain: prim,
        n: if prim == 0 { 2 } else { 1 },
    };
    let bg = visibility::StaticSample {
        rgba: [0.05, 0.1, 0.15, 1.0],
        depth: 3.0,
        id: 1,
    };
    let frags = vec![
        frag(0.0, 0.7, 1.0, 4.0, 0),
        frag(0.1, 0.9, 2.5, 1.5, 1),
        frag(0.3, 1.0, 2.0, 2.2, 2),
        frag(0.55, 0.6, 0.5, 5.0, 3),
    ];
    for shutter in [Shutter::Box, Shutter::Triangle, Shutter::Gaussian] {
        for quad in [Quadrature::Auto, Quadrature::Points(3)] {
            let run = |uniform: bool| {
                let mut l = FlatLayers {
                    colors: colors.clone(),
                    uniform,
                    links: links.clone(),
                };
                let mut f = frags.clone();
                resolve::resolve(
                    &mut f,
                    &links,
                    &bg,
                    &mut l,
                    resolve::Timing {
                        shutter: &shutter,
                        breaks: &shutter.breaks(),
                        quad,
                        t_ref: 0.5,
                        window: None,
                    },
                    &mut resolve::Scratch::default(),
                )
                .unwrap()
            };
            let (a, b) = (run(false), run(true));
            assert_eq!((a.front, a.pieces), (b.front, b.pieces));
            for j in 0..4 {
                assert!(
                    (a.rgba[j] - b.rgba[j]).abs() < 1e-6,
                    "{shutter:?} {a:?} {b:?}"
                );
            }
        }
    }
}

/// The translating square of [`check_square`] (object 7, over nothing) with the exposure
/// channel for 8 objects.
fn render_exposure(shutter: &Shutter, exposure: Option<u32>, samples: u32) -> crate::Result<Frame> {
    let (pos, faces) = grid_square(0.6, 3, &[-1.5, 1.2]);
    let vp = [camera()];
    let rgba = [[1.0f32, 1.0, 1.0, 0.5]];
    let draws = [MovingDraw {
        positions: &pos,
        faces: &faces,
        rgba: &rgba,
        normals: None,
        object_id: 7,
        cull_back: true,
        shading: Shading::Flat,
    }];
    let input = Input {
        width: W,
        height: H,
        samples,
        times: &[0.0, 1.0],
        view_projections: &vp,
        draws: &draws,
        backdrop: None,
        shutter,
        lights: &[],
        ambient: [0.0; 3],
        quadrature: Quadrature::Auto,
        reference_time: 1.0,
        shade: true,
        tile_budget: DEFAULT_TILE_BUDGET,
        rolling: Default::default(),
        exposure,
    };
    render(&input).map(|r| r.0)
}

#[test]
fn exposure_is_the_closed_form_time_in_front_and_changes_nothing_else() {
    let (h, x0, x1) = (0.6, -1.5, 1.2);
    for shutter in [Shutter::Box, Shutter::Ramp] {
        let off = render_exposure(&shutter, None, 1).unwrap();
        let on = render_exposure(&shutter, Some(8), 1).unwrap();
        assert!(off.exposure.is_none());
        let e = on.exposure.clone().expect("asked for");
        assert_eq!((on.rgba, on.depth, on.ids), (off.rgba, off.depth, off.ids));
        assert_eq!(e.planes, 9);
        for iy in 0..H {
            for ix in 0..W {
                let (x, y) = on_plane(ix, iy);
                let i = (iy * W + ix) as usize * 9;
                let (a, b) = (
                    ((x - h - x0) / (x1 - x0)).clamp(0.0, 1.0),
                    ((x + h - x0) / (x1 - x0)).clamp(0.0, 1.0),
                );
                // alpha 0.5: in front (so counted) however transparent
                let inside = y.abs() <= h && b > a;
                let want = if inside {
                    shutter.cumulative(b) - shutter.cumulative(a)
                } else {
                    0.0
                };
                let got = f64::from(e.fraction[i + 7]);
                assert!((got - want).abs() < 1e-5, "({ix}, {iy}): {got} {want}");
                let sum: f32 = e.fraction[i..i + 9].iter().sum();
                assert!((sum - 1.0).abs() < 1e-6, "{sum}");
                assert!(e.fraction[i..i + 7].iter().all(|f| *f == 0.0));
                if inside {
                    assert!((f64::from(e.first[i + 7]) - a).abs() < 1e-5);
                    assert!((f64::from(e.last[i + 7]) - b).abs() < 1e-5);
                } else {
                    assert!(e.first[i + 7].is_nan() && e.last[i + 7].is_nan());
                }
            }
        }
    }
    // supersampled: every pixel's fractions still sum to 1
    let e = render_exposure(&Shutter::Box, Some(8), 2)
        .unwrap()
        .exposure
        .unwrap();
    for p in e.fraction.chunks(9) {
        assert!((p.iter().sum::<f32>() - 1.0).abs() < 1e-6);
    }
}

#[test]
fn exposure_ids_outside_its_objects_and_too_large_planes_are_errors() {
    let e = render_exposure(&Shutter::Box, Some(7), 1).unwrap_err();
    assert!(e.to_string().starts_with("object_id"), "{e}");
    let _lock = crate::budget::tests::BUDGET_LOCK.lock().unwrap();
    let e = render_exposure(&Shutter::Box, Some(4_000_000), 1).unwrap_err();
    assert!(matches!(e, crate::Error::Memory { .. }), "{e}");
    assert!(e.to_string().starts_with("exposure"), "{e}");
}
