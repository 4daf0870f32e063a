//! Whole-pipeline tests of the rasterizer in pure Rust.
use super::camera::look_at;
use super::*;
use crate::frame::Layer;
use glam::{DMat4, DVec3};

fn camera(w: u32, h: u32) -> Camera {
    let pose = look_at(DVec3::new(0.0, 0.0, 3.0), DVec3::ZERO, DVec3::Y).unwrap();
    Camera::new(pose, 0.9, w, h, 0.05, 100.0).unwrap()
}

fn draw(vertices: Vec<[f64; 3]>, faces: Vec<[u32; 3]>, rgba: [f32; 4]) -> Draw {
    Draw {
        vertices,
        faces,
        rgba: vec![rgba],
        normals: None,
        object_id: 7,
        cull_back: true,
        previous: None,
        shading: None,
    }
}

/// A grid of n x n quads (two triangles each) spanning [-1,1]^2 at z = 0, counter-clockwise.
fn grid(n: usize, jitter: f64) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let mut v = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let inner = i > 0 && i < n && j > 0 && j < n;
            let d = if inner {
                jitter * (((i * 7 + j * 13) % 11) as f64 / 11.0 - 0.5)
            } else {
                0.0
            };
            v.push([
                -1.0 + 2.0 * i as f64 / n as f64 + d,
                -1.0 + 2.0 * j as f64 / n as f64 - d,
                0.0,
            ]);
        }
    }
    (v, crate::mesh::grid_faces(n))
}

#[test]
fn a_transparent_mesh_covers_every_sample_exactly_once() {
    // Every pixel inside the grid must hold alpha 0.5 exactly: 0 would be a seam, 0.75 a sample
    // blended twice along a shared edge.
    let (v, f) = grid(9, 0.08);
    let d = draw(v, f, [1.0, 1.0, 1.0, 0.5]);
    let cam = camera(97, 61);
    let (frame, _) = rasterize(&cam, &[d], &Options::default()).unwrap();
    let alphas: Vec<f32> = frame.rgba.chunks(4).map(|c| c[3]).collect();
    assert!(
        alphas.iter().all(|&a| a == 0.0 || a == 0.5),
        "a pixel was blended twice"
    );
    // The centre region is inside the grid: no gaps there.
    for y in 20..40 {
        for x in 35..60 {
            assert_eq!(alphas[y * 97 + x], 0.5, "seam at ({x},{y})");
        }
    }
}

#[test]
fn output_does_not_depend_on_the_thread_count() {
    let (v, f) = grid(40, 0.03);
    let mut d = draw(v.clone(), f, [0.2, 0.6, 0.9, 0.4]);
    d.previous = Some(v.iter().map(|p| [p[0] + 0.01, p[1], p[2] - 0.02]).collect());
    d.cull_back = false;
    let (bv, bf) = grid(3, 0.0);
    let bv = bv.iter().map(|p| [p[0] * 0.7, p[1] * 0.5, -0.3]).collect();
    let back = draw(bv, bf, [0.9, 0.1, 0.1, 1.0]);
    let opts = Options {
        samples: 2,
        ..Default::default()
    };
    let cam = camera(300, 200);
    let run = |threads| {
        crate::on_threads(threads, || {
            rasterize(&cam, &[d.clone(), back.clone()], &opts)
                .unwrap()
                .0
        })
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.rgba, b.rgba);
    assert_eq!(a.depth, b.depth);
    assert_eq!(a.ids, b.ids);
    assert_eq!(a.velocity, b.velocity);
    assert!(a.ids.contains(&7));
}

#[test]
fn depth_is_the_view_axis_distance() {
    // A large quad at z = -2 seen from z = 3: depth 5 everywhere.
    let v = vec![
        [-9.0, -9.0, -2.0],
        [9.0, -9.0, -2.0],
        [9.0, 9.0, -2.0],
        [-9.0, 9.0, -2.0],
    ];
    let d = draw(v, vec![[0, 1, 2], [0, 2, 3]], [0.5, 0.5, 0.5, 1.0]);
    let (frame, _) = rasterize(&camera(32, 24), &[d], &Options::default()).unwrap();
    for z in &frame.depth {
        assert!((z - 5.0).abs() < 5e-6, "{z}");
    }
    assert!(frame.ids.iter().all(|&i| i == 7));
}

#[test]
fn triangles_crossing_the_near_plane_are_clipped_not_dropped() {
    // A floor through the camera position: half of it lies behind the camera.
    let v = vec![[-50.0, -1.0, 50.0], [50.0, -1.0, 50.0], [0.0, -1.0, -50.0]];
    let d = draw(v, vec![[0, 1, 2]], [1.0, 1.0, 1.0, 1.0]);
    let (frame, stats) = rasterize(&camera(64, 48), &[d], &Options::default()).unwrap();
    assert!(stats.clipped >= 1);
    // The lower half of the image sees the floor; depth grows towards the horizon.
    let col = 32;
    let depths: Vec<f32> = (30..48).map(|y| frame.depth[y * 64 + col]).collect();
    assert!(depths.iter().all(|z| z.is_finite()));
    assert!(depths.windows(2).all(|p| p[0] >= p[1]));
    assert!(frame.depth[5 * 64 + col].is_infinite());
}

#[test]
fn back_faces_are_culled_only_when_asked() {
    // Clockwise seen from the camera.
    let v = vec![[-1.0, -1.0, 0.0], [0.0, 1.0, 0.0], [1.0, -1.0, 0.0]];
    let mut d = draw(v, vec![[0, 1, 2]], [1.0, 0.0, 0.0, 1.0]);
    let cam = camera(16, 16);
    let (f, _) = rasterize(&cam, std::slice::from_ref(&d), &Options::default()).unwrap();
    assert!(f.ids.iter().all(|&i| i == -1));
    d.cull_back = false;
    let (f, _) = rasterize(&cam, &[d], &Options::default()).unwrap();
    assert!(f.ids.contains(&7));
}

#[test]
fn velocity_is_the_screen_motion_in_pixels() {
    // A quad at z = 0 moved by dx world units: at distance 3 with yfov 0.9 that is
    // dx * (h / 2) / tan(0.45) / 3 pixels to the right.
    let v = vec![
        [-0.5, -0.5, 0.0],
        [0.5, -0.5, 0.0],
        [0.5, 0.5, 0.0],
        [-0.5, 0.5, 0.0],
    ];
    let mut d = draw(v.clone(), vec![[0, 1, 2], [0, 2, 3]], [1.0; 4]);
    let dx = 0.1;
    d.previous = Some(v.iter().map(|p| [p[0] - dx, p[1] + dx, p[2]]).collect());
    let (f, _) = rasterize(&camera(64, 64), &[d], &Options::default()).unwrap();
    let want = dx * 32.0 / (0.45f64).tan() / 3.0;
    let i = 32 * 64 + 32;
    let velocity = f
        .velocity
        .expect("a draw with previous positions writes velocity");
    assert!((f64::from(velocity[2 * i]) - want).abs() < 1e-4);
    assert!(
        (f64::from(velocity[2 * i + 1]) - want).abs() < 1e-4,
        "y is down: moving up is +y over time"
    );
}

#[test]
fn a_one_pixel_image_and_far_away_coordinates_work() {
    let v = vec![[-1e6, -1e6, -1e6], [1e6, -1e6, -1e6], [0.0, 1e6, -1e6]];
    let d = draw(v, vec![[0, 1, 2]], [1.0; 4]);
    let pose = DMat4::IDENTITY;
    let cam = Camera::new(pose, 1.0, 1, 1, 0.05, 1e7).unwrap();
    let (f, _) = rasterize(&cam, &[d], &Options::default()).unwrap();
    assert_eq!(f.ids, vec![7]);
    assert!((f.depth[0] - 1e6).abs() < 1.0);
}

#[test]
fn bad_options_name_the_argument() {
    assert!(Blend::parse("sorted")
        .unwrap_err()
        .to_string()
        .starts_with("blend"));
    assert!(Shading::parse("phong")
        .unwrap_err()
        .to_string()
        .starts_with("shading"));
    let opts = Options {
        samples: 3,
        ..Default::default()
    };
    let e = rasterize(&camera(8, 8), &[], &opts).unwrap_err();
    assert!(e.to_string().starts_with("samples"));
}

#[test]
fn kept_tile_buffers_change_no_result_even_after_a_very_deep_tile() {
    // 80 transparent layers over a 64x64 image: one tile of 327,680 fragments, more than a
    // thread keeps between tiles, so its lists are released after it. The same frame rendered
    // again, and a shallow frame before and after, must not change.
    let layers: Vec<Draw> = (0..80)
        .map(|k| {
            let z = -0.5 + k as f64 / 80.0;
            let v = vec![
                [-3.0, -3.0, z],
                [3.0, -3.0, z],
                [3.0, 3.0, z],
                [-3.0, 3.0, z],
            ];
            let a = 0.02 + 0.01 * (k % 7) as f32;
            draw(
                v,
                vec![[0, 1, 2], [0, 2, 3]],
                [0.9, 0.5, 0.1 * (k % 5) as f32, a],
            )
        })
        .collect();
    let (v, f) = grid(5, 0.05);
    let shallow = [draw(v, f, [0.2, 0.4, 0.8, 0.5])];
    let cam = camera(64, 64);
    let opts = Options::default();
    let (s0, _) = rasterize(&cam, &shallow, &opts).unwrap();
    let (d0, stats) = rasterize(&cam, &layers, &opts).unwrap();
    assert!(stats.fragments >= 80 * 64 * 64);
    let (d1, _) = rasterize(&cam, &layers, &opts).unwrap();
    let (s1, _) = rasterize(&cam, &shallow, &opts).unwrap();
    assert_eq!(d0.rgba, d1.rgba);
    assert_eq!(d0.ids, d1.ids);
    assert_eq!(s0.rgba, s1.rgba);
    assert_eq!(s0.depth, s1.depth);
}

#[test]
fn a_bad_background_value_anywhere_in_the_window_is_an_error() {
    // The tiles check the background's values as they load them: one bad value in a tile with
    // triangles, in an empty tile or at the last sample fails the frame; outside the window it
    // is never read. 150 x 70 samples: tiles of 64, the triangle in the centre one.
    let (w, h, stride, rows, x0, y0) = (150usize, 70usize, 160usize, 80usize, 5usize, 5usize);
    let d = draw(
        vec![[-0.1, -0.1, 0.0], [0.1, -0.1, 0.0], [0.0, 0.1, 0.0]],
        vec![[0, 1, 2]],
        [0.3, 0.6, 0.9, 0.5],
    );
    let cam = camera(w as u32, h as u32);
    let rgba = vec![0.25f32; 4 * stride * rows];
    let depth = vec![5.0f32; stride * rows]; // behind the triangle (at 3)
    let ids = vec![3i32; stride * rows];
    let render = |rgba: &[f32], depth: &[f32]| {
        let bg = Background {
            layer: Layer {
                width: stride,
                height: rows,
                rgba,
                depth,
                ids: &ids,
            },
            x0,
            y0,
        };
        rasterize_over(
            &cam,
            std::slice::from_ref(&d),
            &Options::default(),
            Some(&bg),
        )
    };
    let (good, stats) = render(&rgba, &depth).unwrap();
    assert!(stats.fragments > 0 && good.ids.contains(&7) && good.ids.contains(&3));
    let index = |x: usize, y: usize| (y + y0) * stride + x + x0;
    for (x, y) in [(75, 35), (70, 30), (10, 66), (w - 1, h - 1), (0, 0)] {
        for bad in [f32::NAN, 0.0, -1.0, f32::NEG_INFINITY] {
            let mut dd = depth.clone();
            dd[index(x, y)] = bad;
            let err = render(&rgba, &dd).expect_err("bad depth");
            assert!(err.to_string().starts_with("background"), "{err}");
        }
        for bad in [f32::NAN, f32::INFINITY] {
            let mut c = rgba.clone();
            c[4 * index(x, y) + 2] = bad;
            let err = render(&c, &depth).expect_err("bad colour");
            assert!(err.to_string().starts_with("background"), "{err}");
        }
    }
    // outside the window: not read, not checked, no change
    let mut dd = depth.clone();
    dd[0] = f32::NAN;
    dd[stride * rows - 1] = -1.0;
    let (same, _) = render(&rgba, &dd).unwrap();
    assert_eq!(same.rgba, good.rgba);
    assert_eq!(same.ids, good.ids);
}

#[test]
fn points_on_the_sample_grid_project_to_the_snapped_corners() {
    // Every point in front of the camera lands on the 1/256-sample grid at its own clip depth
    // (within float64 rounding), moved at most half a grid step; a point behind the camera
    // stays where it is.
    let cam = camera(40, 30);
    let (pts, _) = grid(9, 0.37);
    let mut pts: Vec<[f64; 3]> = pts.iter().map(|p| [p[0], p[1], p[2] - 1.5]).collect();
    pts.push([0.0, 0.0, 50.0]);
    for samples in SAMPLES {
        let out = on_sample_grid(&cam, samples, &pts);
        let m = cam.view_projection();
        let (ws, hs) = (f64::from(40 * samples), f64::from(30 * samples));
        for (p, q) in pts.iter().zip(&out) {
            let (c, d) = (setup::clip_position(&m, p), setup::clip_position(&m, q));
            if c[3] <= 0.0 {
                assert_eq!(p, q);
                continue;
            }
            assert!(
                (d[3] - c[3]).abs() < 1e-9 * c[3] && (d[2] - c[2]).abs() < 1e-9 * c[3].max(1.0)
            );
            for (v, size, flip) in [(d[0] / d[3], ws, false), (d[1] / d[3], hs, true)] {
                let s = if flip {
                    (1.0 - v) * 0.5 * size
                } else {
                    (v + 1.0) * 0.5 * size
                } * 256.0;
                assert!((s - s.round()).abs() < 1e-6, "{s} is not on the grid");
            }
            let moved =
                [(0, ws), (1, hs)].map(|(k, size)| (d[k] / d[3] - c[k] / c[3]).abs() * 0.5 * size);
            assert!(moved.iter().all(|m| *m <= 0.5 / 256.0 + 1e-9), "{moved:?}");
        }
    }
}
