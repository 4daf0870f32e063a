//! Refinement of a motion volume's faces where linear alphas miss the coverage profile.
//!
//! The rasterizer interpolates the vertices' coverage alphas linearly across each face. Where the
//! coverage bends between two vertices, the interpolation is wrong by the bend, and one bend is
//! large and common: along the volume's outline, when the object's image grows, shrinks or turns
//! across its motion. An object moving towards the camera covers a point of the outline only at
//! the instant its image is largest there, so coverage rises from 0 at the outline to its
//! interior value over a band as wide as the image grows, often much narrower than the mesh's
//! faces; a face interpolating 0 to the interior value over its whole width loses coverage (an
//! unrotated box moving across the view and half its size towards the camera lost 18%, and
//! the loss grows with the faces).
//!
//! Each pass tests the edges whose end alphas differ by more than [`TOLERANCE`] and whose image
//! is at least 1/2048 of the volume's: an edge whose midpoint coverage differs from the mean of
//! its ends by more than [`TOLERANCE`] is cut there, and each face is split by the pattern of its
//! cut edges (2, 3 or 4 faces, same orientation). The decision and the midpoint are functions of
//! the edge's two end positions only, so faces that share an edge in space (also through
//! distinct vertices, such as joining strips with their own vertices against the leading and
//! trailing faces) cut it alike: the surface stays watertight. Each split halves the band a face
//! misses; [`LEVELS`] passes. A new vertex takes the mean colour and normal of the edge's ends
//! (what the rasterizer interpolates there) and its own coverage.
//!
//! Three passes leave at most an eighth of the band (the box above: -2.2%). More would chase the
//! model's own steps: its hull is constant within each of its sub-segments, so under perspective
//! or rotation its coverage changes across a band in small steps, which every pass cuts again
//! (the camera-pan scene's volumes: 43k faces and 25 ms of CPU, 76k and 60 ms with three passes,
//! 93k and 73 ms with four). The passes' work is split in fixed chunks and collected in order:
//! the result is the same for any thread count.
use rayon::prelude::*;

use super::coverage::CoverageModel;

/// Coverage difference (alpha) that makes an edge a candidate and, at its midpoint, cuts it.
pub const TOLERANCE: f64 = 0.02;

/// Passes of refinement (each halves the band of coverage a face can miss).
pub const LEVELS: usize = 3;

/// Faces, and edges to test, per parallel task: the passes are short, and on a busy machine
/// waking threads for small volumes costs more than the work.
const PAR_FACES: usize = 16_384;
const PAR_EDGES: usize = 2048;

/// A volume's surface during refinement: placed vertices, faces, their parts and the vertices'
/// coverage (the filter's alpha), straight colours and normals.
pub(crate) struct Surface {
    pub vertices: Vec<[f64; 3]>,
    pub faces: Vec<[u32; 3]>,
    pub part: Vec<u8>,
    pub cover: Vec<f64>,
    pub colors: Vec<[f32; 4]>,
    pub normals: Vec<[f32; 3]>,
    /// Per face, whether refinement tests its edges (faces the camera cannot see are cut only
    /// where a tested face is, so that the image does not depend on them); empty: every face.
    pub testable: Vec<bool>,
}

/// The bits of a position, for ordering and comparing edges by their ends in space.
fn bits(p: [f64; 3]) -> [u64; 3] {
    p.map(f64::to_bits)
}

/// An edge by its ends in space, smaller end first.
type SpaceEdge = ([u64; 3], [u64; 3]);

fn space_edge(a: [f64; 3], b: [f64; 3]) -> SpaceEdge {
    let (x, y) = (bits(a), bits(b));
    if x <= y {
        (x, y)
    } else {
        (y, x)
    }
}

/// Cut the faces of `s` where linear alphas miss `model`'s coverage (see the module docs).
pub(crate) fn refine(model: &CoverageModel, s: &mut Surface) {
    if s.faces.is_empty() {
        return;
    }
    // The smallest edge worth cutting: 1/2048 of the volume's image.
    let (lo, hi) = s
        .faces
        .iter()
        .flatten()
        .map(|&i| model.image(s.vertices[i as usize]))
        .fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(l, h), q| {
            (
                [l[0].min(q[0]), l[1].min(q[1])],
                [h[0].max(q[0]), h[1].max(q[1])],
            )
        });
    let min_edge = (hi[0] - lo[0]).max(hi[1] - lo[1]) / 2048.0;
    if min_edge.is_nan() || min_edge <= 0.0 {
        return;
    }
    for _ in 0..LEVELS {
        if !refine_once(model, s, min_edge) {
            break;
        }
    }
}

/// One pass; `false` when nothing was cut.
fn refine_once(model: &CoverageModel, s: &mut Surface, min_edge: f64) -> bool {
    // Candidate edges by vertex pair (smaller index first), with their edge in space and whether
    // a tested face has them.
    let (cover, vertices, testable) = (&s.cover, &s.vertices, &s.testable);
    let mut pairs: Vec<((u32, u32), SpaceEdge, bool)> = s
        .faces
        .par_iter()
        .enumerate()
        .with_min_len(PAR_FACES)
        .flat_map_iter(|(fi, f)| {
            let tested = testable.get(fi).copied().unwrap_or(true);
            (0..3).filter_map(move |k| {
                let (i, j) = (f[k], f[(k + 1) % 3]);
                let (ci, cj) = (cover[i as usize], cover[j as usize]);
                if (ci - cj).abs() <= TOLERANCE {
                    return None;
                }
                let (p, q) = (vertices[i as usize], vertices[j as usize]);
                let (a, b) = (model.image(p), model.image(q));
                if (a[0] - b[0]).hypot(a[1] - b[1]) < min_edge {
                    return None;
                }
                Some(((i.min(j), i.max(j)), space_edge(p, q), tested))
            })
        })
        .collect();
    if pairs.is_empty() {
        return false;
    }
    pairs.sort_unstable();
    // One entry per pair, tested when any of its faces is (`true` sorts last).
    pairs.reverse();
    pairs.dedup_by(|a, b| a.0 == b.0);
    pairs.reverse();
    // Each edge in space of a tested face once, in order, with its ends' mean coverage (the same
    // for every vertex pair on it: coverage is a function of the position); then the decision
    // per edge in space, the midpoint and its coverage when it is cut.
    let mut edges: Vec<(SpaceEdge, f64)> = pairs
        .iter()
        .filter(|p| p.2)
        .map(|&((i, j), e, _)| (e, 0.5 * (cover[i as usize] + cover[j as usize])))
        .collect();
    edges.sort_unstable_by_key(|a| a.0);
    edges.dedup_by(|a, b| a.0 == b.0);
    let decided: Vec<Option<([f64; 3], f64)>> = edges
        .par_iter()
        .with_min_len(PAR_EDGES)
        .map(|&(e, mean)| {
            let (p, q) = (e.0.map(f64::from_bits), e.1.map(f64::from_bits));
            let mid = [
                0.5 * (p[0] + q[0]),
                0.5 * (p[1] + q[1]),
                0.5 * (p[2] + q[2]),
            ];
            let cm = model.coverage(mid);
            ((cm - mean).abs() > TOLERANCE).then_some((mid, cm))
        })
        .collect();
    // A new vertex per cut vertex pair, in pair order: `cut_pairs` sorted, `touched` its ends.
    let mut cut_pairs: Vec<((u32, u32), u32)> = Vec::new();
    let mut touched = vec![false; s.vertices.len()];
    // Every pair on a cut edge in space is cut, also on faces that are not tested.
    for &((i, j), e, _) in &pairs {
        let Ok(k) = edges.binary_search_by(|x| x.0.cmp(&e)) else {
            continue;
        };
        let Some((mid, cm)) = decided[k] else {
            continue;
        };
        cut_pairs.push(((i, j), s.vertices.len() as u32));
        (touched[i as usize], touched[j as usize]) = (true, true);
        let (i, j) = (i as usize, j as usize);
        s.vertices.push(mid);
        s.cover.push(cm);
        let (a, b) = (s.colors[i], s.colors[j]);
        s.colors.push([0, 1, 2, 3].map(|k| 0.5 * (a[k] + b[k])));
        let (a, b) = (s.normals[i], s.normals[j]);
        let n = [0, 1, 2].map(|k| 0.5 * (a[k] + b[k]));
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        s.normals
            .push(if len > 0.0 { n.map(|x| x / len) } else { n });
    }
    if cut_pairs.is_empty() {
        return false;
    }
    let cut = |i: u32, j: u32| {
        if !(touched[i as usize] && touched[j as usize]) {
            return None;
        }
        let key = (i.min(j), i.max(j));
        cut_pairs
            .binary_search_by(|x| x.0.cmp(&key))
            .ok()
            .map(|k| cut_pairs[k].1)
    };
    let mut faces = Vec::with_capacity(s.faces.len() + 3 * cut_pairs.len());
    let mut part = Vec::with_capacity(faces.capacity());
    let mut tested = Vec::with_capacity(if s.testable.is_empty() {
        0
    } else {
        faces.capacity()
    });
    for (fi, (f, &tag)) in s.faces.iter().zip(&s.part).enumerate() {
        let [a, b, c] = *f;
        let pieces = split(a, b, c, cut(a, b), cut(b, c), cut(c, a));
        for t in pieces.iter().flatten() {
            faces.push(*t);
            part.push(tag);
            if let Some(&x) = s.testable.get(fi) {
                tested.push(x);
            }
        }
    }
    s.faces = faces;
    s.part = part;
    s.testable = tested;
    true
}

/// The counter-clockwise face `a b c` split at the midpoints `ab`, `bc`, `ca` it has: itself,
/// 2, 3 or 4 faces, the same orientation.
fn split(
    a: u32,
    b: u32,
    c: u32,
    ab: Option<u32>,
    bc: Option<u32>,
    ca: Option<u32>,
) -> [Option<[u32; 3]>; 4] {
    match (ab, bc, ca) {
        (None, None, None) => [Some([a, b, c]), None, None, None],
        (Some(m), None, None) => [Some([a, m, c]), Some([m, b, c]), None, None],
        (None, Some(m), None) => [Some([a, b, m]), Some([a, m, c]), None, None],
        (None, None, Some(m)) => [Some([a, b, m]), Some([m, b, c]), None, None],
        (Some(x), Some(y), None) => [Some([x, b, y]), Some([a, x, y]), Some([a, y, c]), None],
        (None, Some(y), Some(z)) => [Some([y, c, z]), Some([a, b, y]), Some([a, y, z]), None],
        (Some(x), None, Some(z)) => [Some([z, a, x]), Some([x, b, c]), Some([x, c, z]), None],
        (Some(x), Some(y), Some(z)) => [
            Some([a, x, z]),
            Some([x, b, y]),
            Some([z, y, c]),
            Some([x, y, z]),
        ],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Twice the signed area of a triangle of points in the plane.
    fn area2(p: &[[f64; 2]], t: [u32; 3]) -> f64 {
        let [a, b, c] = t.map(|i| p[i as usize]);
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    }

    #[test]
    fn every_split_pattern_tiles_the_face_in_its_orientation() {
        // a b c and the midpoints of ab, bc, ca as 3, 4, 5.
        let p = [
            [0.0, 0.0],
            [2.0, 0.0],
            [0.0, 2.0],
            [1.0, 0.0],
            [1.0, 1.0],
            [0.0, 1.0],
        ];
        for mask in 0..8u32 {
            let m = |k: u32| (mask >> k & 1 == 1).then_some(3 + k);
            let pieces = split(0, 1, 2, m(0), m(1), m(2));
            let mut total = 0.0;
            for t in pieces.iter().flatten() {
                let a = area2(&p, *t);
                assert!(a > 0.0, "mask {mask}: {t:?}");
                total += a;
            }
            assert!((total - area2(&p, [0, 1, 2])).abs() < 1e-12, "mask {mask}");
            assert_eq!(
                pieces.iter().flatten().count(),
                1 + mask.count_ones() as usize
            );
        }
    }
}
