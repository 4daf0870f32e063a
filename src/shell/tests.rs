//! Core tests of the blur shell: silhouette rule, strips, fading bounds, threads.
use std::collections::HashMap;

use super::locality::Locality;
use super::*;
use crate::contour::{face_edge, BACK, FRONT, NEUTRAL, NO_EDGE};
use crate::mesh::uv_sphere as sphere;

fn moved(v: &[[f64; 3]], t: [f64; 3]) -> Vec<[f64; 3]> {
    v.iter()
        .map(|p| [p[0] + t[0], p[1] + t[1], p[2] + t[2]])
        .collect()
}

fn shell(f: &[[u32; 3]], nv: usize, s: u32, h: u32) -> BlurShell {
    let opts = ShellOptions {
        subdivisions: s,
        hysteresis: h,
        initial_alpha: 0.8,
    };
    BlurShell::new(
        f.to_vec(),
        nv,
        opts,
        None,
        ShellColor::Uniform([1.0, 0.5, 0.25, 1.0]),
    )
    .unwrap()
}

#[test]
fn facing_rule_and_face_edge() {
    let fac = [FRONT, BACK, BACK, NEUTRAL];
    assert_eq!(face_edge(&fac, &[0, 1, 2]), 1);
    assert_eq!(face_edge(&fac, &[1, 0, 2]), 2);
    assert_eq!(face_edge(&fac, &[1, 2, 0]), 0);
    assert_eq!(face_edge(&fac, &[0, 1, 3]), NO_EDGE);
    assert_eq!(face_edge(&[BACK, BACK, BACK], &[0, 1, 2]), NO_EDGE);
}

#[test]
fn translating_sphere_has_attached_monotone_strips() {
    let (v, f) = sphere(12, 24);
    let mut sh = shell(&f, v.len(), 6, 2);
    for i in 0..8 {
        sh.update(&moved(&v, [0.1 * i as f64, 0.0, 0.0]), None)
            .unwrap();
    }
    let cur = moved(&v, [0.1 * 7.0, 0.0, 0.0]);
    let m = sh.build(Some(&cur), None).unwrap();
    // Without positions, the base is the float32 snapshot of the last update.
    let d = sh.build(None, None).unwrap();
    assert_eq!(d.faces, m.faces);
    for (a, b) in d.vertices.iter().zip(&m.vertices) {
        assert!((0..3).all(|i| (a[i] - b[i]).abs() <= 1e-6));
    }
    assert!(!m.faces.is_empty());
    let mut by_face: HashMap<u32, Vec<usize>> = HashMap::new();
    for (i, &fi) in m.face.iter().enumerate() {
        by_face.entry(fi).or_default().push(i);
    }
    for (fi, idx) in by_face {
        let face = f[fi as usize];
        // Base pair on the current mesh, at a silhouette edge (a back-facing edge: x < 0.7 side).
        let base: Vec<usize> = idx.iter().copied().filter(|&i| m.step[i] == 0).collect();
        assert_eq!(base.len(), 2);
        for &b in &base {
            assert!(
                face.iter().any(|&c| cur[c as usize] == m.vertices[b]),
                "not attached"
            );
        }
        // Alpha never rises along the strip; steps are consecutive; ends at zero (full strip).
        for w in idx.windows(2) {
            assert!(m.rgba[w[1]][3] <= m.rgba[w[0]][3]);
        }
        let last = idx[idx.len() - 1];
        assert_eq!(m.step[last] as usize, idx.len() / 2 - 1);
        if m.step[last] == 6 {
            assert_eq!(m.rgba[last][3], 0.0);
        }
        // Strip vertices trail behind: x decreases along the strip.
        assert!(m.vertices[last][0] < m.vertices[base[0]][0] - 0.05);
    }
}

#[test]
fn static_mesh_has_no_strip() {
    let (v, f) = sphere(8, 16);
    let mut sh = shell(&f, v.len(), 4, 1);
    for _ in 0..5 {
        sh.update(&v, None).unwrap();
    }
    assert!(sh.build(None, None).unwrap().faces.is_empty());
    assert!(sh.facing().iter().all(|&x| x == NEUTRAL));
}

/// Strip vertices keyed by (face, recorded update, side): the base of a build after update m
/// is "recorded" at m + 1 (it becomes ring element 0 at the next update).
type Keyed = HashMap<(u32, i64, usize), f32>;

fn keyed(sh: &BlurShell, m: &ShellMesh) -> Keyed {
    let upd = sh.updates() as i64;
    let mut out = HashMap::new();
    for i in 0..m.face.len() {
        let rec = upd - m.step[i] as i64;
        out.insert((m.face[i], rec, i % 2), m.rgba[i][3]);
    }
    out
}

fn assert_no_popping(
    s: u32,
    h: u32,
    seq: &[Vec<[f64; 3]>],
    f: &[[u32; 3]],
    normals: Option<&[Vec<[f64; 3]>]>,
) {
    let mut sh = shell(f, seq[0].len(), s, h);
    let step = 0.8 / s as f32 + 1e-6;
    let mut before: Option<(Keyed, std::collections::HashSet<u32>)> = None;
    for (k, v) in seq.iter().enumerate() {
        sh.update(v, normals.map(|n| &n[k][..])).unwrap();
        let m = sh.build(None, None).unwrap();
        let now = keyed(&sh, &m);
        let faces_now: std::collections::HashSet<u32> = m.face.iter().copied().collect();
        if let Some((prev, faces_prev)) = &before {
            for (key, &a) in prev {
                match now.get(key) {
                    Some(&b) => assert!((a - b).abs() <= step, "update {k}: {key:?} {a} -> {b}"),
                    None => assert!(a <= step, "update {k}: {key:?} vanished at alpha {a}"),
                }
            }
            for (key, &b) in &now {
                if !prev.contains_key(key) && faces_prev.contains(&key.0) {
                    // New element of a live strip: only the new base, which continues the old base.
                    let old = prev.get(&(key.0, key.1 - 1, key.2)).copied().unwrap_or(0.0);
                    assert!(
                        (b - old).abs() <= step,
                        "update {k}: new {key:?} {old} -> {b}"
                    );
                }
            }
        }
        before = Some((now, faces_now));
    }
}

#[test]
fn no_popping_on_a_wobbling_deforming_sphere() {
    let (v, f) = sphere(10, 20);
    let seq: Vec<Vec<[f64; 3]>> = (0..40)
        .map(|t| {
            let t = t as f64 * 0.37;
            v.iter()
                .map(|p| {
                    let w = (3.0 * p[2] + t).sin() * 0.3;
                    [
                        p[0] + w + (t * 0.7).cos() * 0.2,
                        p[1] + (t * 1.3).sin() * 0.1,
                        p[2],
                    ]
                })
                .collect()
        })
        .collect();
    assert_no_popping(6, 2, &seq, &f, None);
    assert_no_popping(3, 0, &seq, &f, None);
    assert_no_popping(1, 5, &seq, &f, None);
    // Normals that flip sign every few updates.
    let normals: Vec<Vec<[f64; 3]>> = (0..40)
        .map(|t| {
            let s = if (t / 3) % 2 == 0 { 1.0 } else { -1.0 };
            v.iter().map(|p| [s * p[0], s * p[1], s * p[2]]).collect()
        })
        .collect();
    assert_no_popping(5, 1, &seq, &f, Some(&normals));
}

#[test]
fn stopping_mesh_fades_out_after_hysteresis_plus_subdivisions() {
    let (v, f) = sphere(8, 16);
    let (s, h) = (4u32, 2u32);
    let mut sh = shell(&f, v.len(), s, h);
    for i in 0..5 {
        sh.update(&moved(&v, [0.0, 0.2 * i as f64, 0.0]), None)
            .unwrap();
    }
    let rest = moved(&v, [0.0, 0.8, 0.0]);
    let full = sh.build(None, None).unwrap().faces.len();
    assert!(full > 0);
    for k in 1..=(h + s) {
        sh.update(&rest, None).unwrap();
        let m = sh.build(None, None).unwrap();
        if k <= h {
            assert!(!m.faces.is_empty());
            assert!(m.rgba.iter().filter(|c| c[3] > 0.0).all(|c| c[3] <= 0.8));
        }
        if k == h + s {
            assert!(
                m.faces.is_empty(),
                "strips still alive after h + s updates at rest"
            );
        } else {
            assert!(!m.faces.is_empty(), "strips vanished early at {k}");
        }
    }
}

#[test]
fn mask_removes_exactly_the_masked_strips() {
    let (v, f) = sphere(8, 16);
    let mask: Vec<bool> = (0..f.len()).map(|i| i % 3 != 0).collect();
    let opts = ShellOptions::default();
    let mut a = BlurShell::new(
        f.clone(),
        v.len(),
        opts,
        None,
        ShellColor::Uniform([1.0; 4]),
    )
    .unwrap();
    let mut b = BlurShell::new(
        f.clone(),
        v.len(),
        opts,
        Some(mask.clone()),
        ShellColor::Uniform([1.0; 4]),
    )
    .unwrap();
    for i in 0..6 {
        let p = moved(&v, [0.1 * i as f64, 0.05 * i as f64, 0.0]);
        a.update(&p, None).unwrap();
        b.update(&p, None).unwrap();
    }
    let (ma, mb) = (a.build(None, None).unwrap(), b.build(None, None).unwrap());
    let keep: Vec<usize> = (0..ma.face.len())
        .filter(|&i| mask[ma.face[i] as usize])
        .collect();
    assert!(keep.len() < ma.face.len());
    assert_eq!(keep.len(), mb.face.len());
    for (j, &i) in keep.iter().enumerate() {
        assert_eq!(ma.vertices[i], mb.vertices[j]);
        assert_eq!(ma.rgba[i], mb.rgba[j]);
        assert_eq!(ma.face[i], mb.face[j]);
    }
}

#[test]
fn thread_count_does_not_change_the_shell() {
    // Large enough for the parallel path (2 * 119 * 160 faces >= PAR_MIN_FACES).
    let (v, f) = sphere(120, 160);
    let run = || {
        let mut sh = shell(&f, v.len(), 5, 2);
        assert!(sh.parallel());
        for i in 0..7 {
            let t = i as f64 * 0.1;
            let p: Vec<[f64; 3]> = v
                .iter()
                .map(|p| [p[0] + t * p[2], p[1], p[2] + t * t])
                .collect();
            sh.update(&p, None).unwrap();
        }
        sh.build(None, None).unwrap()
    };
    let a = crate::on_threads(1, run);
    let b = crate::on_threads(3, run);
    assert!(!a.faces.is_empty());
    assert_eq!(a, b);
}

#[test]
fn bad_input_names_the_argument() {
    let (v, f) = sphere(6, 8);
    let mut sh = shell(&f, v.len(), 3, 1);
    let e = sh.update(&v[..v.len() - 1], None).unwrap_err();
    assert!(e.to_string().starts_with("vertices"), "{e}");
    let mut bad = v.clone();
    bad[3][1] = f64::NAN;
    assert!(sh
        .update(&bad, None)
        .unwrap_err()
        .to_string()
        .starts_with("vertices"));
    assert!(sh
        .update(&v, Some(&v[..2]))
        .unwrap_err()
        .to_string()
        .starts_with("normals"));
    assert_eq!(sh.updates(), 0);
    let o = |s, a| ShellOptions {
        subdivisions: s,
        hysteresis: 0,
        initial_alpha: a,
    };
    let c = ShellColor::Uniform([1.0; 4]);
    let new = |opts, mask, color| BlurShell::new(f.clone(), v.len(), opts, mask, color);
    assert!(new(o(0, 1.0), None, c.clone())
        .unwrap_err()
        .to_string()
        .starts_with("subdivisions"));
    assert!(new(o(3, 0.0), None, c.clone())
        .unwrap_err()
        .to_string()
        .starts_with("initial_alpha"));
    assert!(new(o(3, f32::NAN), None, c.clone()).is_err());
    assert!(new(o(3, 1.0), Some(vec![true]), c.clone())
        .unwrap_err()
        .to_string()
        .starts_with("mask"));
    let e = new(o(3, 1.0), None, ShellColor::Uniform([-1.0, 0.0, 0.0, 1.0])).unwrap_err();
    assert!(e.to_string().starts_with("color"));
    let e = BlurShell::new(vec![[0, 1, 99]], 3, o(3, 1.0), None, c).unwrap_err();
    assert!(e.to_string().starts_with("faces"));
}

#[test]
fn locality_is_a_bijection_with_faces_sorted_and_sums_in_original_order() {
    let (v, f) = sphere(9, 17);
    let loc = Locality::new(&f, v.len());
    let mut seen = vec![false; v.len()];
    for (i, &p) in loc.perm.iter().enumerate() {
        assert!(!seen[p as usize]);
        seen[p as usize] = true;
        assert_eq!(loc.inv[p as usize] as usize, i);
    }
    assert!(loc
        .bfaces
        .windows(2)
        .all(|w| w[0].iter().min() <= w[1].iter().min()));
    for (fi, face) in f.iter().enumerate() {
        let i = face.map(|x| loc.inv[x as usize]);
        assert_eq!(loc.ifaces[fi], i);
    }
    // Every internal vertex lists its faces in increasing original face order.
    let slot_to_orig: HashMap<[u32; 3], usize> = loc
        .ifaces
        .iter()
        .enumerate()
        .map(|(k, &x)| (x, k))
        .collect();
    for iv in 0..v.len() {
        let orig: Vec<usize> = loc
            .vf
            .faces_of(iv)
            .iter()
            .map(|&b| slot_to_orig[&loc.bfaces[b as usize]])
            .collect();
        assert!(
            orig.windows(2).all(|w| w[0] < w[1]),
            "vertex {iv}: {orig:?}"
        );
        assert!(!orig.is_empty());
    }
}

#[test]
fn paired_unit_normals_equal_normalize_bit_for_bit() {
    let one = |n: [f32; 3]| {
        let u = crate::mesh::normalize([n[0] as f64, n[1] as f64, n[2] as f64]);
        [u[0] as f32, u[1] as f32, u[2] as f32]
    };
    let mut cases: Vec<[f32; 3]> = vec![
        [0.0; 3],
        [-0.0, 0.0, -0.0],
        [1e-45, 0.0, 0.0],
        [3e38, 3e38, -3e38],
        [f32::INFINITY, 0.0, 0.0],
        [f32::NAN, 1.0, 0.0],
        [0.0, 0.0, -2.5],
    ];
    let mut x = 0x2545_f491_u32;
    for _ in 0..2000 {
        let mut r = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            f32::from_bits(x & 0x8000_0000 | (x % 0x4000_0000 + 0x1000_0000))
        };
        cases.push([r(), r(), r()]);
    }
    for w in cases.windows(2) {
        let got = super::build::unit2(w[0], w[1]);
        for (g, n) in got.iter().zip([w[0], w[1]]) {
            assert_eq!(g.map(f32::to_bits), one(n).map(f32::to_bits), "{n:?}");
        }
    }
}

#[test]
fn a_colour_alpha_scales_every_strip_alpha_and_keeps_the_geometry() {
    // A translucent object's trail: the colour's alpha multiplies the strip's own alpha (the
    // fraction of the shutter a point is covered), per mesh vertex; alpha 1 is the plain shell.
    let (v, f) = sphere(10, 20);
    let opts = ShellOptions {
        subdivisions: 5,
        hysteresis: 1,
        initial_alpha: 0.8,
    };
    let per_vertex: Vec<[f32; 4]> = (0..v.len())
        .map(|i| [0.5, 0.5, 0.5, (i % 7) as f32 / 6.0])
        .collect();
    let colours = [
        ShellColor::Uniform([0.5, 0.5, 0.5, 1.0]),
        ShellColor::Uniform([0.5, 0.5, 0.5, 0.3]),
        ShellColor::PerVertex(per_vertex.clone()),
    ];
    let built: Vec<ShellMesh> = colours
        .into_iter()
        .map(|c| {
            let mut sh = BlurShell::new(f.clone(), v.len(), opts, None, c).unwrap();
            for i in 0..6 {
                sh.update(&moved(&v, [0.08 * i as f64, 0.02 * i as f64, 0.0]), None)
                    .unwrap();
            }
            sh.build(None, None).unwrap()
        })
        .collect();
    let (plain, third, each) = (&built[0], &built[1], &built[2]);
    assert!(!plain.faces.is_empty());
    for m in [third, each] {
        assert_eq!(m.faces, plain.faces);
        assert_eq!(m.vertices, plain.vertices);
        assert_eq!(m.step, plain.step);
    }
    for (w, p) in plain.rgba.iter().enumerate() {
        assert_eq!(third.rgba[w][3], p[3] * 0.3);
        // The strip vertex's mesh vertex: the base pair is on the mesh, so its alpha is one of
        // the per-vertex alphas times the strip's; every vertex of a strip pair keeps its own.
        let a = each.rgba[w][3];
        assert!(
            per_vertex.iter().any(|c| a == p[3] * c[3]),
            "{a} is not the strip alpha {} times a vertex alpha",
            p[3]
        );
    }
    let e = BlurShell::new(
        f.clone(),
        v.len(),
        opts,
        None,
        ShellColor::Uniform([1.0, 1.0, 1.0, 1.5]),
    );
    assert!(e.unwrap_err().to_string().starts_with("color"));
}
