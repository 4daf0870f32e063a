//! Which contour edges of a face split a motion volume sweeps, and which of their sides face
//! the camera (section 3.2's contour line, and the joining strips of a path that turns).
use rayon::prelude::*;

use crate::contour::{contour_line, ContourEdge};
use crate::mesh::Mesh;
use crate::motion::Path;

/// The `contour` edges of a face split (from `front`); with the camera sides of the faces
/// (facing the camera at close, at open), the contour line and, per edge, whether its leading
/// (front faces at close) and trailing (back faces at open) sides face the camera.
///
/// With `strips` (the path and the eye, for a path that turns) an edge is also kept when a
/// triangle of its joining strip between two keyframes faces the eye: a turning object shows
/// strips of edges whose faces face away both at close (leading side) and at open (trailing
/// side), and dropping them emptied the frame of a box that turned 1.4 rad while moving 2 units
/// (the section 3.2 contour line assumes a translation).
pub(crate) fn select_contour(
    mesh: &Mesh,
    contour: Vec<ContourEdge>,
    front: &[bool],
    sides: Option<&(Vec<bool>, Vec<bool>)>,
    strips: Option<(&Path, [f64; 3])>,
) -> (Vec<ContourEdge>, Vec<(bool, bool)>) {
    let Some((vis_lead, vis_trail)) = sides else {
        return (contour, Vec::new());
    };
    let visible: Vec<bool> = (0..front.len())
        .into_par_iter()
        .map(|f| if front[f] { vis_lead[f] } else { vis_trail[f] })
        .collect();
    let contour = match strips {
        None => contour_line(mesh, contour, &visible),
        Some((path, eye)) => {
            let adj = mesh.adjacency();
            let verts = mesh.vertices();
            contour
                .into_par_iter()
                .filter(|c| {
                    adj.incident(c.edge as usize)
                        .iter()
                        .any(|&h| visible[(h / 3) as usize])
                        || strip_faces(path, verts[c.a as usize], verts[c.b as usize], eye)
                })
                .collect()
        }
    };
    let adj = mesh.adjacency();
    let vis = contour
        .par_iter()
        .map(|c| {
            let inc = adj.incident(c.edge as usize);
            let lead = inc
                .iter()
                .any(|&h| front[(h / 3) as usize] && vis_lead[(h / 3) as usize]);
            let trail = inc
                .iter()
                .any(|&h| !front[(h / 3) as usize] && vis_trail[(h / 3) as usize]);
            (lead, trail)
        })
        .collect();
    (contour, vis)
}

/// Whether a triangle of the joining strip of the edge `(a, b)` (object space) between two
/// keyframes of `path` faces `eye`, as `assemble.rs` emits them: `a0 b0 b1` and `a0 b1 a1`,
/// counter-clockwise.
fn strip_faces(path: &Path, a: [f64; 3], b: [f64; 3], eye: [f64; 3]) -> bool {
    let sub = |p: [f64; 3], q: [f64; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
    let cross = |u: [f64; 3], v: [f64; 3]| {
        [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ]
    };
    let facing = |p: [f64; 3], q: [f64; 3], r: [f64; 3]| {
        crate::mesh::dot(cross(sub(q, p), sub(r, p)), sub(eye, p)) > 0.0
    };
    path.frames.windows(2).any(|w| {
        let (a0, b0) = (w[0].point(a), w[0].point(b));
        let (a1, b1) = (w[1].point(a), w[1].point(b));
        facing(a0, b0, b1) || facing(a0, b1, a1)
    })
}
