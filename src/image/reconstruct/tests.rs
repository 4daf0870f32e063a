//! The reconstruction's tests: against the every-tap oracle, the plain gather, any thread count.
use super::*;

fn params() -> ReconstructParams {
    ReconstructParams {
        samples: 16,
        tile: 8,
        soft_depth: 0.01,
    }
}

#[test]
fn no_motion_copies_the_frame() {
    let (w, h) = (13, 7);
    let rgba: Vec<f32> = (0..w * h * 4).map(|i| (i % 11) as f32 / 11.0).collect();
    let depth = vec![2.0f32; w * h];
    let vel = vec![0.0f32; w * h * 2];
    let out = reconstruct(&rgba, &depth, &vel, w, h, params()).unwrap();
    assert_eq!(out, rgba);
}

#[test]
fn a_moving_square_spreads_and_keeps_its_coverage() {
    // a 10-pixel opaque square moving 12 pixels right over nothing
    let (w, h) = (48, 20);
    let mut rgba = vec![0.0f32; w * h * 4];
    let mut depth = vec![f32::INFINITY; w * h];
    let mut vel = vec![0.0f32; w * h * 2];
    for y in 5..15 {
        for x in 19..29 {
            let i = y * w + x;
            rgba[i * 4..i * 4 + 4].copy_from_slice(&[1.0, 0.5, 0.25, 1.0]);
            depth[i] = 3.0;
            vel[i * 2] = 12.0;
        }
    }
    let out = reconstruct(&rgba, &depth, &vel, w, h, params()).unwrap();
    let alpha = |x: usize| out[(10 * w + x) * 4 + 3];
    // the streak reaches 6 pixels past each edge, fading
    assert!(alpha(16) > 0.05 && alpha(16) < 0.9, "{}", alpha(16));
    assert!(alpha(10) < 1e-6);
    // total coverage of the row is kept within 15%
    let total: f32 = (0..w).map(alpha).sum();
    assert!((total - 10.0).abs() < 1.5, "{total}");
    // colour stays premultiplied: rgb = alpha * colour
    let i = (10 * w + 17) * 4;
    assert!((out[i] - out[i + 3]).abs() < 1e-5);
    assert!((out[i + 1] - 0.5 * out[i + 3]).abs() < 1e-5);
}

#[test]
fn max_speed_is_the_longest_length() {
    // the root of the largest squared length against the largest root, with tails of every
    // length and chunks of several threads
    for n in [0usize, 1, 7, 9, 5000, 20001] {
        let v: Vec<f32> = (0..2 * n)
            .map(|i| ((i * 7919 % 1013) as f32 - 506.0) * 0.37)
            .collect();
        let want = v.chunks_exact(2).fold(0.0f64, |m, p| {
            m.max(((p[0] as f64).powi(2) + (p[1] as f64).powi(2)).sqrt())
        });
        assert_eq!(max_speed(&v).to_bits(), want.to_bits(), "{n}");
        if n > 0 {
            let mut bad = v.clone();
            bad[2 * n - 1] = f32::NAN;
            assert!(max_speed(&bad).is_nan());
        }
    }
}

#[test]
fn max_speed_in_a_window_is_its_copys() {
    // the window read in place against a copy of it: inside, at the edges, one row, empty,
    // a NaN inside and outside the window
    let (w, h) = (45, 31);
    let mut v: Vec<f32> = (0..2 * w * h)
        .map(|i| ((i * 7919 % 1013) as f32 - 506.0) * 0.37)
        .collect();
    let copy = |v: &[f32], (y0, y1, x0, x1): Window| -> Vec<f32> {
        (y0..y1)
            .flat_map(|y| v[2 * (y * w + x0)..2 * (y * w + x1)].to_vec())
            .collect()
    };
    let windows = [
        (0, 31, 0, 45),
        (3, 20, 5, 17),
        (30, 31, 0, 45),
        (4, 4, 2, 9),
        (0, 5, 44, 45),
    ];
    for win in windows {
        let want = max_speed(&copy(&v, win));
        assert_eq!(
            max_speed_in(&v, w, win).to_bits(),
            want.to_bits(),
            "{win:?}"
        );
    }
    v[2 * (6 * w + 9) + 1] = f32::NAN;
    assert!(max_speed_in(&v, w, (6, 7, 9, 10)).is_nan());
    assert!(!max_speed_in(&v, w, (7, 31, 0, 45)).is_nan());
}

#[test]
fn same_result_on_one_thread() {
    let (w, h) = (40, 30);
    let rgba: Vec<f32> = (0..w * h * 4).map(|i| (i % 7) as f32 / 7.0).collect();
    let depth: Vec<f32> = (0..w * h).map(|i| 1.0 + (i % 5) as f32).collect();
    let vel: Vec<f32> = (0..w * h * 2).map(|i| (i % 9) as f32 - 4.0).collect();
    let a = reconstruct(&rgba, &depth, &vel, w, h, params()).unwrap();
    let b = crate::on_threads(1, || {
        reconstruct(&rgba, &depth, &vel, w, h, params()).unwrap()
    });
    assert_eq!(a, b);
}

#[test]
fn a_moving_window_gives_the_whole_frames_bits() {
    // velocities 0 outside a window: reading only the window's gives the bits of reading them
    // all, for windows inside, at the edges, one row, empty, tiles not multiples of the cells
    // (the tile and cell maxima are taken by absolute boundaries), on any thread count; a
    // window outside the image is refused
    let (w, h) = (70, 45);
    let rgba: Vec<f32> = (0..w * h * 4)
        .map(|i| (i * 37 % 101) as f32 / 101.0)
        .collect();
    let depth: Vec<f32> = (0..w * h)
        .map(|i| 1.0 + (i * 13 % 17) as f32 * 0.3)
        .collect();
    let windows = [
        (10, 30, 20, 50),
        (0, 45, 0, 9),
        (20, 45, 61, 70),
        (7, 8, 0, 70),
        (5, 5, 3, 3),
    ];
    for (y0, y1, x0, x1) in windows {
        let mut vel = vec![0.0f32; w * h * 2];
        for y in y0..y1 {
            for x in x0..x1 {
                let i = y * w + x;
                vel[2 * i] = ((i * 7 % 23) as f32 - 11.0) * 1.3;
                vel[2 * i + 1] = ((i * 5 % 19) as f32 - 9.0) * 0.7;
            }
        }
        for tile in [6, 8, 21] {
            let p = ReconstructParams { tile, ..params() };
            let whole = reconstruct(&rgba, &depth, &vel, w, h, p).unwrap();
            let win = (y0, y1, x0, x1);
            let part = reconstruct_moving(&rgba, &depth, &vel, (w, h), p, win).unwrap();
            assert_eq!(whole, part, "{win:?} {tile}");
            let one = crate::on_threads(1, || {
                reconstruct_moving(&rgba, &depth, &vel, (w, h), p, win).unwrap()
            });
            assert_eq!(whole, one, "{win:?} {tile}");
        }
    }
    let vel = vec![0.0f32; w * h * 2];
    for win in [(0, 46, 0, 10), (3, 2, 0, 10), (0, 10, 0, 71)] {
        let e = reconstruct_moving(&rgba, &depth, &vel, (w, h), params(), win).unwrap_err();
        assert!(e.to_string().contains("moving"), "{e}");
    }
}

/// The gather of every tap of every pixel, serial: the filter as the module docs define it,
/// without the cells' skipping (the oracle of the skipping).
fn unskipped(
    rgba: &[f32],
    depth: &[f32],
    vel: &[f32],
    (w, h): (usize, usize),
    p: ReconstructParams,
) -> Vec<f32> {
    let (half, _) = half_velocities(vel, p.tile as f32).unwrap();
    let (tx, nmax) = neighbour_max(&half, w, h, p.tile);
    let mut out = vec![0.0f32; w * h * 4];
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let n = nmax[(y / p.tile) * tx + x / p.tile];
            let c = half[i];
            let (rn, rc) = (len2(n).sqrt(), len2(c).sqrt());
            if rn.max(rc) < 0.5 {
                out[i * 4..i * 4 + 4].copy_from_slice(&rgba[i * 4..i * 4 + 4]);
                continue;
            }
            let zx = depth[i];
            let (mut fg, mut bg) = ([0.0f32; 4], [0.0f32; 4]);
            let (mut wf, mut wb, mut taps) = (0.0f32, 0.0f32, 0.0f32);
            let mut tap = |yi: usize, d: f32| {
                let zy = depth[yi];
                let f = if zx == zy {
                    0.5
                } else {
                    (0.5 - (zy - zx) / (p.soft_depth * zx.min(zy))).clamp(0.0, 1.0)
                };
                let a = f * (len2(half[yi]).sqrt() - d + 1.0).clamp(0.0, 1.0);
                let b = (1.0 - f) * (rc - d + 1.0).clamp(0.0, 1.0);
                for k in 0..4 {
                    fg[k] += a * rgba[yi * 4 + k];
                    bg[k] += b * rgba[yi * 4 + k];
                }
                wf += a;
                wb += b;
                taps += 1.0;
            };
            tap(i, 0.0);
            let pairs = p.samples / 2;
            let both = rc >= 0.5 && rn >= 0.5;
            // the pixel's run of eight: from its tile's left edge, eight pixels at a time
            let x0 = x - (x % p.tile) % 8;
            let j = jitter(x0, y);
            // a moving pixel's own direction: its run's first moving pixel's half velocity
            let end = ((x0 / p.tile + 1) * p.tile).min(w).min(x0 + 8);
            let first = (x0..end).find(|&k| len2(half[y * w + k]).sqrt() >= 0.5);
            let cr = half[y * w + first.unwrap_or(x)];
            for q in 0..pairs {
                // the tap of the run's first pixel moved along the row
                let (dir, r, k, m, a) = if both && q % 2 == 1 {
                    (cr, len2(cr).sqrt(), q / 2, pairs / 2, x0)
                } else if both {
                    (n, rn, q / 2, pairs - pairs / 2, x0)
                } else {
                    (n, rn, q, pairs, x0)
                };
                let t = (k as f32 + j) / m.max(1) as f32;
                for s in [-1.0f32, 1.0] {
                    let px = a as f32 + 0.5 + s * t * dir[0];
                    let py = y as f32 + 0.5 + s * t * dir[1];
                    let sx = px.floor() as i64 + (x - a) as i64;
                    if sx < 0 || py < 0.0 || sx >= w as i64 || py >= h as f32 {
                        continue;
                    }
                    let (sx, sy) = (sx as usize, py as usize);
                    let dx = (sx as f32 - x as f32).powi(2) + (sy as f32 - y as f32).powi(2);
                    tap(sy * w + sx, dx.sqrt().min(t * r));
                }
            }
            let fill = (1.0 - (wf + wb) / taps).clamp(0.0, 1.0);
            for k in 0..4 {
                let back = if wb > 0.0 {
                    bg[k] / wb
                } else {
                    rgba[i * 4 + k]
                };
                out[i * 4 + k] = (fg[k] + bg[k]) * (1.0 / taps) + back * fill;
            }
        }
    }
    out
}

#[test]
fn skipped_taps_give_the_bits_of_every_tap() {
    // a wide still frame (most cells far from motion, borders, sky) with a few moving
    // blocks of several speeds and directions, some of them slow (under half a pixel)
    let (w, h) = (150, 90);
    let mut rgba: Vec<f32> = (0..w * h * 4)
        .map(|i| ((i * 7919) % 1000) as f32 / 1000.0)
        .collect();
    let mut depth: Vec<f32> = (0..w * h).map(|i| 5.0 + (i % 13) as f32 * 0.1).collect();
    let mut vel = vec![0.0f32; w * h * 2];
    let blocks = [
        (10, 30, 12, 28, [30.0f32, 0.0], 2.0f32),
        (70, 80, 40, 70, [-9.0, 13.0], 3.0),
        (120, 140, 5, 15, [0.6, -0.5], 1.5),
        (40, 44, 80, 90, [3.0, 40.0], 4.0),
    ];
    for &(x0, x1, y0, y1, v, z) in &blocks {
        for y in y0..y1 {
            for x in x0..x1 {
                let i = y * w + x;
                vel[i * 2..i * 2 + 2].copy_from_slice(&v);
                depth[i] = z;
                rgba[i * 4 + 3] = 1.0;
            }
        }
    }
    depth[..w].fill(f32::INFINITY); // a sky row
    for samples in [2, 8, 16, 30] {
        for tile in [1, 4, 8, 20, 64] {
            let p = ReconstructParams {
                samples,
                tile,
                soft_depth: 0.01,
            };
            let fast = reconstruct(&rgba, &depth, &vel, w, h, p).unwrap();
            let slow = unskipped(&rgba, &depth, &vel, (w, h), p);
            let same = fast
                .iter()
                .zip(&slow)
                .all(|(a, b)| a.to_bits() == b.to_bits());
            assert!(same, "samples {samples} tile {tile}");
        }
    }
}

#[test]
fn vector_gather_gives_the_plain_bits_on_any_thread_count() {
    // moving blocks of every direction and several speeds (moving lanes, still lanes and
    // mixes in one group of eight), a sky (inf depth), slow motion under half a pixel,
    // taps off every edge; tiles that are not multiples of 8 (scalar tails), odd pair
    // counts (a moving pixel's directions alternate unevenly)
    let (w, h) = (203, 97);
    let rgba: Vec<f32> = (0..w * h * 4)
        .map(|i| ((i * 7919) % 1000) as f32 / 1000.0)
        .collect();
    let mut depth: Vec<f32> = (0..w * h).map(|i| 4.0 + (i % 17) as f32 * 0.05).collect();
    let mut vel = vec![0.0f32; w * h * 2];
    let blocks = [
        (3, 40, 2, 30, [45.0f32, 3.0], 2.0f32),
        (90, 97, 40, 80, [-11.0, 27.0], 3.0),
        (150, 200, 60, 95, [0.7, -0.4], 1.5),
        (60, 70, 85, 97, [-60.0, -70.0], 4.5),
        (120, 125, 0, 12, [8.0, 0.0], 20.0),
    ];
    for &(x0, x1, y0, y1, v, z) in &blocks {
        for y in y0..y1 {
            for x in x0..x1 {
                let i = y * w + x;
                // velocities vary along the block, so that lanes differ
                let k = 1.0 + (x % 5) as f32 * 0.1;
                vel[i * 2..i * 2 + 2].copy_from_slice(&[v[0] * k, v[1] * k]);
                depth[i] = z;
            }
        }
    }
    for d in depth[..3 * w].iter_mut() {
        *d = f32::INFINITY;
    }
    let run = || {
        let mut all = Vec::new();
        for samples in [2, 6, 16, 32] {
            for tile in [7, 8, 13, 40, 100] {
                let p = ReconstructParams {
                    samples,
                    tile,
                    soft_depth: 0.02,
                };
                all.extend(reconstruct(&rgba, &depth, &vel, w, h, p).unwrap());
            }
        }
        all
    };
    let _guard = crate::simd::SWITCH
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let before = crate::simd::set_simd(true);
    let vector = run();
    let one = crate::on_threads(1, run);
    let two = crate::on_threads(2, run);
    crate::simd::set_simd(false);
    let plain = run();
    crate::simd::set_simd(before);
    let same = |a: &[f32], b: &[f32]| a.iter().zip(b).all(|(p, q)| p.to_bits() == q.to_bits());
    assert_eq!(vector.len(), plain.len());
    assert!(same(&vector, &plain), "vector against plain");
    assert!(same(&one, &plain) && same(&two, &plain), "thread counts");
}

/// Runs of eight pixels `still8` gave (any test's).
pub(super) static STILL_RUNS: std::sync::atomic::AtomicUsize =
    std::sync::atomic::AtomicUsize::new(0);
/// Of those, the runs `still8_avx` gave.
pub(super) static STILL_VECTOR_RUNS: std::sync::atomic::AtomicUsize =
    std::sync::atomic::AtomicUsize::new(0);

#[test]
fn still_runs_give_the_gathers_bits() {
    // one small fast mover near the left edge, the rest of a wide image still: beyond the
    // mover's reach the runs of eight are their centre tap and a count (`still8`, in AVX2
    // where the run's first tap is past its stop and every tap inside the image), near it and
    // at the image's edges (taps off the image) they are gathered; tiles that cover the
    // whole image and tiles that do not (still tiles copied); subnormal colours
    let (w, h) = (1003, 40);
    let rgba: Vec<f32> = (0..w * h * 4)
        .map(|i| ((i * 7919) % 1000) as f32 / 1000.0 + if i % 97 == 0 { 1e-39 } else { 0.0 })
        .map(|v| if v > 0.999 { 3e-39 } else { v })
        .collect();
    let mut depth: Vec<f32> = (0..w * h).map(|i| 4.0 + (i % 13) as f32 * 0.05).collect();
    depth[w * 20..w * 22].fill(f32::INFINITY);
    let mut vel = vec![0.0f32; w * h * 2];
    for y in 10..20 {
        for x in 0..12 {
            vel[(y * w + x) * 2] = 600.0 - x as f32;
            vel[(y * w + x) * 2 + 1] = 3.0;
        }
    }
    let cases = [(16, 200), (16, 31), (6, 150), (32, 700), (2, 90)];
    let run = |(samples, tile)| {
        let p = ReconstructParams {
            samples,
            tile,
            soft_depth: 0.02,
        };
        (reconstruct(&rgba, &depth, &vel, w, h, p).unwrap(), p)
    };
    let _guard = crate::simd::SWITCH
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let before = crate::simd::set_simd(true);
    let count = |c: &std::sync::atomic::AtomicUsize| c.load(std::sync::atomic::Ordering::Relaxed);
    let (runs, vector_runs) = (count(&STILL_RUNS), count(&STILL_VECTOR_RUNS));
    let vector: Vec<_> = cases.into_iter().map(run).collect();
    let (runs, vector_runs) = (
        count(&STILL_RUNS) - runs,
        count(&STILL_VECTOR_RUNS) - vector_runs,
    );
    crate::simd::set_simd(false);
    let plain: Vec<_> = cases.into_iter().map(|c| run(c).0).collect();
    crate::simd::set_simd(before);
    if crate::simd::simd_enabled() {
        assert!(runs > 3000, "still8 ran on {runs} runs");
        assert!(vector_runs > 1000, "still8_avx ran on {vector_runs} runs");
    }
    for ((v, p), q) in vector.iter().zip(&plain) {
        let oracle = unskipped(&rgba, &depth, &vel, (w, h), *p);
        let same = |a: &[f32], b: &[f32]| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits());
        assert!(same(v, q), "vector against plain, {p:?}");
        assert!(same(v, &oracle), "vector against every tap, {p:?}");
    }
}

#[test]
fn bad_input_names_the_argument() {
    let (w, h) = (4, 4);
    let rgba = vec![0.0f32; w * h * 4];
    let depth = vec![1.0f32; w * h];
    let vel = vec![0.0f32; w * h * 2];
    let mut p = params();
    p.samples = 1;
    let e = reconstruct(&rgba, &depth, &vel, w, h, p).unwrap_err();
    assert!(e.to_string().contains("samples"));
    let e = reconstruct(&rgba, &[0.0; 16], &vel, w, h, params()).unwrap_err();
    assert!(e.to_string().contains("depth"));
}
