//! Unit tests of the image kernels in pure Rust: invariants and thread-count independence.
//! (The numpy twins in tests/image_twins.py check the values.)
use super::lines::plan;
use super::*;
use crate::on_threads;
use crate::simd::{set_simd, SWITCH};

fn image(w: usize, h: usize, seed: u32) -> Vec<f32> {
    // A small deterministic generator: an alpha blob with random-ish colours.
    let mut s = seed.wrapping_mul(2654435761).wrapping_add(1);
    let mut rnd = move || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        (s % 10000) as f32 / 10000.0
    };
    let mut out = Vec::with_capacity(w * h * 4);
    for y in 0..h {
        for x in 0..w {
            let d =
                ((x as f32 - w as f32 * 0.4).powi(2) + (y as f32 - h as f32 * 0.5).powi(2)).sqrt();
            let a = (w.min(h) as f32 * 0.3 - d).clamp(0.0, 1.0);
            out.extend([rnd() * a, rnd() * a, rnd() * a, a]);
        }
    }
    out
}

#[test]
fn glow_never_lowers_alpha() {
    let (w, h) = (53, 31);
    let img = image(w, h, 1);
    let alpha: Vec<f32> = img.chunks(4).map(|p| p[3]).collect();
    for d in [[1.0, 0.0], [0.0, 1.0], [1.0, 0.4], [-0.3, 1.0]] {
        let g = glow(&alpha, w, h, d, 7.0).unwrap();
        assert!(g.iter().zip(&alpha).all(|(g, a)| g >= a));
    }
}

#[test]
fn opaque_blur_of_a_constant_is_the_constant() {
    let (w, h) = (40, 30);
    let img: Vec<f32> = (0..w * h).flat_map(|_| [0.2, 0.4, 0.1, 1.0]).collect();
    for d in [[1.0, 0.0], [0.0, 1.0], [1.0, 0.6]] {
        let out = opaque_blur(&img, w, h, d, 11.0).unwrap();
        assert!(out.iter().zip(&img).all(|(o, i)| (o - i).abs() < 1e-6));
    }
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let (w, h) = (97, 61);
    let img = image(w, h, 2);
    let depth: Vec<f32> = (0..w * h).map(|i| 1.0 + (i % w) as f32 * 0.05).collect();
    let run = || {
        let mut all = Vec::new();
        for d in [[1.0, 0.0], [0.0, 1.0], [1.0, 0.577]] {
            all.extend(opaque_motion_blur(&img, None, w, h, d, 21.0, Composite::Over).unwrap());
            all.extend(box_blur(&img, w, h, d, 21.0).unwrap());
        }
        all.extend(pyramid_opaque_blur(&img, w, h, 3).unwrap());
        let p = DofParams {
            focal_depth: 2.0,
            focal_length: 0.05,
            f_number: 1.4,
            yfov: 0.8,
            layers: 5,
        };
        all.extend(depth_of_field(&img, &depth, w, h, &p).unwrap());
        let lens = LensParams {
            aperture: 0.2,
            focus_distance: 2.5,
            yfov: 0.8,
        };
        all.extend(lens_blur(&img, &depth, w, h, &lens).unwrap());
        all
    };
    let one = on_threads(1, run);
    let two = on_threads(2, run);
    let three = on_threads(3, run);
    assert!(one
        .iter()
        .zip(&two)
        .all(|(a, b)| a.to_bits() == b.to_bits()));
    assert!(one
        .iter()
        .zip(&three)
        .all(|(a, b)| a.to_bits() == b.to_bits()));
}

#[test]
fn lens_blur_keeps_the_focal_plane_and_a_uniform_image() {
    let (w, h) = (57, 43);
    let lens = LensParams {
        aperture: 0.3,
        focus_distance: 3.0,
        yfov: 0.7,
    };
    // all at the focus: unchanged, bit for bit
    let img = image(w, h, 4);
    let focal = vec![3.0f32; w * h];
    assert_eq!(lens_blur(&img, &focal, w, h, &lens).unwrap(), img);
    // a uniform opaque image at scattered depths (and sky) stays uniform and opaque
    let flat: Vec<f32> = (0..w * h).flat_map(|_| [0.2, 0.5, 0.1, 1.0]).collect();
    let depth: Vec<f32> = (0..w * h)
        .map(|i| match i % 7 {
            0 => f32::INFINITY,
            k => 0.5 + k as f32 * 1.3,
        })
        .collect();
    let out = lens_blur(&flat, &depth, w, h, &lens).unwrap();
    assert!(out.iter().zip(&flat).all(|(o, i)| (o - i).abs() < 1e-5));
    // bad lens parameters name themselves
    for (bad, name) in [
        (
            LensParams {
                aperture: 0.0,
                ..lens
            },
            "aperture",
        ),
        (
            LensParams {
                focus_distance: f64::NAN,
                ..lens
            },
            "focus_distance",
        ),
        (LensParams { yfov: 3.5, ..lens }, "yfov"),
    ] {
        let e = lens_blur(&img, &focal, w, h, &bad).unwrap_err();
        assert!(e.to_string().starts_with(name), "{e}");
    }
    let mut neg = focal.clone();
    neg[3] = -1.0;
    assert!(lens_blur(&img, &neg, w, h, &lens)
        .unwrap_err()
        .to_string()
        .starts_with("depth"));
}

#[test]
fn bad_input_names_the_argument() {
    let img = image(8, 6, 3);
    let e = box_blur(&img[..10], 8, 6, [1.0, 0.0], 3.0).unwrap_err();
    assert!(e.to_string().starts_with("rgba"));
    let e = box_blur(&img, 8, 6, [f32::NAN, 0.0], 3.0).unwrap_err();
    assert!(e.to_string().starts_with("direction"));
    let e = box_blur(&img, 8, 6, [1.0, 0.0], -1.0).unwrap_err();
    assert!(e.to_string().starts_with("length"));
    let e = pyramid_blur(&img, 8, 6, 99).unwrap_err();
    assert!(e.to_string().starts_with("levels"));
    let mut bad = img.clone();
    bad[5] = f32::INFINITY;
    let e = opaque_blur(&bad, 8, 6, [1.0, 0.0], 3.0).unwrap_err();
    assert!(e.to_string().starts_with("rgba"));
}

#[test]
fn line_plan_radius_and_axis() {
    let p = plan([1.0, 0.0], 50.5).unwrap();
    assert_eq!((p.transpose, p.slope, p.radius), (false, 0.0, 50));
    let p = plan([0.5, -2.0], 10.0).unwrap();
    assert!(p.transpose && (p.slope + 0.25).abs() < 1e-12);
    assert!(plan([0.0, 0.0], 10.0).is_none());
    assert!(plan([1.0, 0.0], 0.9).is_none());
}

#[test]
fn sheared_buffer_is_bounded_by_the_image() {
    // Every column meets at most h + 1 sheared rows, so the buffer holds at most w (h + 1)
    // pixels whatever the slope (a full rows x w buffer is about w^2 |t| for a long thin image).
    let copy = |src: &[f32], _n: usize, out: &mut [f32], _s: &mut ()| {
        out.copy_from_slice(src);
        true
    };
    for (w, h) in [(100_000usize, 1usize), (20_000, 2), (300, 7), (5, 40)] {
        let img = vec![1.0f32; w * h];
        for t in [0.5, -0.5, 1.0, -0.999, 0.01] {
            let sh = super::lines::build_sheared::<1, 1, ()>(
                "alpha",
                &img,
                w,
                h,
                t,
                0.0,
                super::lines::Live::All,
                &copy,
            )
            .unwrap();
            assert!(
                sh.data.len() <= w * (h + 1),
                "{w}x{h} t={t}: {}",
                sh.data.len()
            );
            // Sheared back, an image of ones is ones away from the top and bottom rows (which
            // interpolate with the zeros outside) and within [0, 1] everywhere.
            let mut row = vec![0.0f32; w];
            for y in 0..h {
                sh.unshear_row(w, y, &mut row);
                assert!(row.iter().all(|v| (-1e-6..=1.0 + 1e-5).contains(v)));
                if y > 0 && y + 1 < h {
                    assert!(
                        row.iter().all(|v| (v - 1.0).abs() < 1e-5),
                        "{w}x{h} t={t} y={y}"
                    );
                }
            }
        }
    }
}

#[test]
fn vector_and_plain_forms_give_the_same_bits() {
    // Images with opaque stretches (the fast paths), soft edges, ragged spans and a base.
    let (w, h) = (131, 67);
    let blob = image(w, h, 7);
    let opaque: Vec<f32> = blob
        .chunks(4)
        .flat_map(|p| [p[0], p[1], p[2], 1.0])
        .collect();
    let base = image(w, h, 8);
    let run = || {
        let mut all = Vec::new();
        for img in [&blob, &opaque] {
            for d in [
                [1.0, 0.0],
                [-1.0, 0.0],
                [0.0, 1.0],
                [1.0, 0.577],
                [1.0, -0.3],
                [0.4, -1.0],
            ] {
                for len in [3.0, 21.0, 90.0] {
                    all.extend(opaque_blur(img, w, h, d, len).unwrap());
                    for c in [Composite::Over, Composite::Under] {
                        all.extend(opaque_motion_blur(img, Some(&base), w, h, d, len, c).unwrap());
                    }
                    all.extend(box_blur(img, w, h, d, len).unwrap());
                }
            }
        }
        all
    };
    let _guard = SWITCH.lock().unwrap_or_else(|e| e.into_inner());
    let before = set_simd(true);
    let vector = run();
    set_simd(false);
    let plain = run();
    set_simd(before);
    assert_eq!(vector.len(), plain.len());
    assert!(vector
        .iter()
        .zip(&plain)
        .all(|(a, b)| a.to_bits() == b.to_bits()));
}

#[test]
fn kernels_that_assume_premultiplied_alpha_refuse_other_alphas() {
    let (w, h) = (37, 5);
    for bad in [1.0 + f32::EPSILON, -1e-6, 1e19, f32::NAN] {
        let mut rgba = vec![0.0f32; w * h * 4];
        rgba[(2 * w + 30) * 4 + 3] = bad;
        let alpha: Vec<f32> = rgba.chunks(4).map(|p| p[3]).collect();
        let clean = vec![0.0f32; w * h * 4];
        for dir in [[1.0, 0.0], [1.0, 0.4], [0.0, 1.0]] {
            assert!(opaque_blur(&rgba, w, h, dir, 3.0).is_err(), "{bad} {dir:?}");
            let e = opaque_motion_blur(&clean, Some(&rgba), w, h, dir, 3.0, Composite::Over);
            assert!(
                e.unwrap_err().to_string().starts_with("base:"),
                "{bad} {dir:?}"
            );
            assert!(glow(&alpha, w, h, dir, 3.0).is_err());
        }
        assert!(pyramid_glow(&alpha, w, h, 2).is_err());
        assert!(pyramid_opaque_blur(&rgba, w, h, 2).is_err());
        assert!(pyramid_blur(&rgba, w, h, 2).is_ok() != bad.is_nan());
    }
    let mut ends = vec![0.0f32; w * h * 4];
    ends[3] = 1.0;
    ends[7] = -0.0;
    assert!(opaque_blur(&ends, w, h, [1.0, 0.3], 3.0).is_ok());
    assert!(check_premultiplied("rgba", &ends, 4).is_ok());
}

#[test]
fn row_check_of_premultiplied_colour_is_the_same_in_both_forms() {
    use super::opaque_row::premultiplied;
    let specials = [
        0.0,
        -0.0,
        1.0,
        0.5,
        1.0 + f32::EPSILON,
        -1e-6,
        1e19,
        -1e19,
        f32::NAN,
        -f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::MIN_POSITIVE,
        -f32::MIN_POSITIVE,
    ];
    let clean = image(13, 1, 3);
    for n in [1, 3, 4, 5, 8, 13] {
        let row = &clean[..n * 4];
        let simd = simd();
        assert!(premultiplied(row, false) && premultiplied(row, simd));
        for at in 0..n * 4 {
            for v in specials {
                let mut r = row.to_vec();
                r[at] = v;
                let want = r.iter().all(|v| v.is_finite())
                    && r.chunks(4).all(|p| !alpha_out_of_range(p[3].to_bits()));
                assert_eq!(premultiplied(&r, false), want, "{n} {at} {v}");
                assert_eq!(premultiplied(&r, simd), want, "{n} {at} {v}");
            }
        }
    }
}

/// A shear told which pixels can be non-zero (`lines::Live::Alpha`) skips the sheared rows that
/// read none of them and gives, sheared back, the values of the shear that builds every row: a
/// sparse mask (a few scattered pixels, a thin diagonal band, one column, nothing) cut from a
/// blob, box-filtered along slopes of either sign, short and longer than the image. A zero may
/// come out as -0 where every row gives +0 (a skipped row is not added in as +0); added to a sum
/// from +0, as `coverage_blur` adds each blurred layer, the bits are the same.
#[test]
fn a_shear_told_its_live_pixels_gives_the_same_values() {
    use super::lines::{build_sheared, Live};
    let (w, h) = (61, 37);
    let blob = image(w, h, 11);
    let masks: [&dyn Fn(usize, usize) -> bool; 4] = [
        &|x, y| (x * 7 + y * 13) % 41 == 0,
        &|x, y| (x as i64 - 2 * y as i64).abs() < 3,
        &|x, _| x == w - 1,
        &|_, _| false,
    ];
    for keep in masks {
        let mut layer = blob.clone();
        for y in 0..h {
            for x in 0..w {
                if !keep(x, y) {
                    layer[(y * w + x) * 4..(y * w + x) * 4 + 4].fill(0.0);
                }
            }
        }
        for t in [0.577, -0.3, 0.05, -1.0] {
            for radius in [1, 10, 75] {
                let f = boxblur::box_filter(radius);
                let all = build_sheared::<4, 4, ()>("rgba", &layer, w, h, t, 0.0, Live::All, &f);
                let live = Live::Alpha(&layer);
                let some = build_sheared::<4, 4, ()>("rgba", &layer, w, h, t, 0.0, live, &f);
                let (all, some) = (all.unwrap(), some.unwrap());
                for y in 0..h {
                    for x in 0..w {
                        let v = |s: &super::lines::Sheared<4>| {
                            s.value(x, y)
                                .unwrap_or([0.0; 4])
                                .map(|v| (0.0 + v).to_bits())
                        };
                        assert_eq!(v(&all), v(&some), "slope {t}, radius {radius}, ({x}, {y})");
                    }
                }
            }
        }
    }
}
