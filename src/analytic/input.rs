//! What a frame of the analytic method is given, its checks, and the per-draw preparation
//! (clip positions and normals at every segment boundary).
use std::borrow::Cow;

use glam::{DMat4, DVec4};
use rayon::prelude::*;

use super::clip::{ClipTable, Marks};
use super::quadrature::Quadrature;
use crate::error::{Error, Result};
use crate::frame::Layer;
use crate::raster::{check_size, vertex_normals, Light, Shading};
use crate::shutter::Shutter;

/// One mesh moving over the shutter.
#[derive(Clone, Copy, Debug)]
pub struct MovingDraw<'a> {
    /// World positions at every segment boundary, boundary-major: `(K+1) * V` points.
    pub positions: &'a [[f64; 3]],
    /// Triangles, counter-clockwise is front.
    pub faces: &'a [[u32; 3]],
    /// Straight linear RGBA: one for every vertex, or one per vertex (`V`).
    pub rgba: &'a [[f32; 4]],
    /// World normals at every boundary (`(K+1) * V`), or None: area-weighted vertex normals of
    /// the positions (used by lambert shading only).
    pub normals: Option<&'a [[f32; 3]]>,
    /// Written to the frame's ids.
    pub object_id: i32,
    /// Drop back faces.
    pub cull_back: bool,
    /// How the draw is shaded.
    pub shading: Shading,
}

/// Everything one frame needs.
#[derive(Clone, Debug)]
pub struct Input<'a> {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel along each axis (1, 2 or 4).
    pub samples: u32,
    /// The segment boundaries: `K + 1` strictly increasing shutter times from 0 to 1.
    pub times: &'a [f64],
    /// The camera's view-projection (OpenGL clip space) at every boundary, or one for all.
    pub view_projections: &'a [DMat4],
    /// The moving meshes.
    pub draws: &'a [MovingDraw<'a>],
    /// The opaque static scene behind them, if any: one entry per sample (`width * samples`
    /// x `height * samples`), depth `inf` and id -1 where nothing is there.
    pub backdrop: Option<Layer<'a>>,
    /// The shutter filter.
    pub shutter: &'a Shutter,
    /// Directional lights (lambert shading).
    pub lights: &'a [Light],
    /// Ambient light (lambert shading).
    pub ambient: [f32; 3],
    /// Points in time per visible piece.
    pub quadrature: Quadrature,
    /// The instant depth, ids and velocity describe, in [0, 1].
    pub reference_time: f64,
    /// False: coverage only (every surface white and unlit), no shading.
    pub shade: bool,
    /// Most bytes one pass over a tile may hold in fragments, links and prims (per thread);
    /// past it the tile is done in smaller passes, with the same result ([`DEFAULT_TILE_BUDGET`]).
    /// Twice it: most bytes of prims set up at once; past it the frame is set up and rendered
    /// strip by strip of tile rows, with the same result.
    pub tile_budget: usize,
    /// The exposure channel ([`crate::Exposure`]) for object ids `0..n`, or None (off: the
    /// frame has none, and the render is the same bits). Every draw's `object_id` and every
    /// backdrop id must then lie in `-1..n`. Visible at a sample and an instant is the object
    /// of the frontmost fragment, whatever its alpha (faces of alpha 0 at every corner are not
    /// drawn), else the backdrop's where it has a surface, else -1; a sample's fraction is the
    /// filter's weight of those instants, its first and last the ends of the stretches of
    /// positive length (whatever their weight); a pixel's, the mean of its samples' fractions
    /// and the earliest first and latest last.
    pub exposure: Option<u32>,
    /// A rolling shutter, or the default: a global one ([`Rolling`]).
    pub rolling: Rolling,
}

/// A rolling shutter: each image row is exposed over its own window of the scene's time.
///
/// Pixel row `y` (0 at the top) of an image `H` pixels high is exposed over `[o, o + 1 - R]`
/// with `o = R y / H` (top to bottom) or `o = R (H - 1 - y) / H` (`bottom_to_top`), `R` the
/// `readout` in [0, 1); every sample of a pixel uses its pixel's row. The shutter filter
/// applies within each row's window, rescaled to it; depth, ids and velocity describe the
/// instant `o + (1 - R) reference_time`. `R = 0` (the default) is a global shutter, resolved
/// as before, bit for bit.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rolling {
    /// The fraction `R` of the frame time the readout takes, in [0, 1).
    pub readout: f64,
    /// False: the readout runs from the top row down; true: from the bottom row up.
    pub bottom_to_top: bool,
}

impl Rolling {
    /// Pixel row `y`'s window `(o, s)` in an image `height` pixels high, or None for a global
    /// shutter.
    pub fn window(&self, y: i32, height: u32) -> Option<(f64, f64)> {
        if self.readout == 0.0 {
            return None;
        }
        let h = f64::from(height);
        let y = f64::from(y);
        let k = if self.bottom_to_top { h - 1.0 - y } else { y };
        Some((self.readout * k / h, 1.0 - self.readout))
    }
}

/// The default of [`Input::tile_budget`]: 64 MiB.
pub const DEFAULT_TILE_BUDGET: usize = 64 << 20;

/// A draw's positions in clip space and its normals at every boundary.
pub struct Prepared<'a> {
    /// Vertices per boundary.
    pub nv: usize,
    /// Where the clip positions are read ([`Prepared::clip_at`]).
    clip: Clip<'a>,
    /// The world positions at every boundary and the camera's view-projection at each (or one).
    positions: &'a [[f64; 3]],
    view_projections: &'a [DMat4],
    /// `(K+1) * V` world normals (lambert): the draw's own, borrowed, or computed; else empty.
    pub normals: Cow<'a, [[f32; 3]]>,
    /// The draw's alpha range per face is read from here: all corners opaque.
    pub opaque_everywhere: bool,
    /// The premultiplied colour every triangle of the draw shows at every point, when shading
    /// cannot vary: flat shading of one colour for all vertices, or no shading at all.
    pub uniform: Option<[f32; 4]>,
}

/// Where a draw's clip positions come from: all computed once (a frame set up whole), computed
/// when asked (a frame set up strip by strip, before a strip's table), or a strip's table of
/// the points its triangles use (`clip.rs`). Each is the same product, so the same bits.
enum Clip<'a> {
    Dense(Vec<[f64; 4]>),
    Direct,
    Table(&'a ClipTable),
}

fn finite3(p: &[f64; 3]) -> bool {
    p.iter().all(|x| x.is_finite())
}

/// Checks the input; errors name the argument.
pub fn validate(input: &Input) -> Result<()> {
    check_size(input.width, input.height, input.samples)?;
    validate_times(input.times)?;
    let k1 = input.times.len();
    let nvp = input.view_projections.len();
    if nvp != 1 && nvp != k1 {
        return Err(Error::shape(
            "view_projections",
            format!("expected 1 or {k1} matrices (one per boundary), got {nvp}"),
        ));
    }
    if input
        .view_projections
        .iter()
        .any(|m| !m.to_cols_array().iter().all(|x| x.is_finite()))
    {
        return Err(Error::value("view_projections", "must be finite"));
    }
    if !(0.0..=1.0).contains(&input.reference_time) {
        return Err(Error::value("reference_time", "must be in [0, 1]"));
    }
    if !(0.0..1.0).contains(&input.rolling.readout) {
        return Err(Error::value("rolling", "must be in [0, 1)"));
    }
    if let Quadrature::Points(n) = input.quadrature {
        if !(1..=4).contains(&n) {
            return Err(Error::value("gauss", "must be 1 to 4 points (or auto)"));
        }
    }
    if input.ambient.iter().any(|x| !x.is_finite() || *x < 0.0) {
        return Err(Error::value("ambient", "must be finite and >= 0"));
    }
    for d in input.draws {
        validate_draw(d, k1)?;
    }
    if input.tile_budget == 0 {
        return Err(Error::value("tile_budget", "must be at least 1 byte"));
    }
    validate_exposure(input)?;
    if let Some(b) = &input.backdrop {
        validate_backdrop(b, input)?;
    }
    Ok(())
}

/// The segment boundaries: at least two, from 0 to 1, strictly increasing.
fn validate_times(t: &[f64]) -> Result<()> {
    if t.len() < 2 {
        return Err(Error::shape(
            "times",
            "needs at least 2 boundaries (0 and 1)",
        ));
    }
    if t[0] != 0.0 || t[t.len() - 1] != 1.0 {
        return Err(Error::value("times", "must start at 0 and end at 1"));
    }
    if t.windows(2).any(|w| !(w[1] > w[0])) {
        return Err(Error::value("times", "must be strictly increasing"));
    }
    Ok(())
}

/// One draw's positions (`k1` boundaries of V vertices each), faces, colours and normals.
fn validate_draw(d: &MovingDraw, k1: usize) -> Result<()> {
    let n = d.positions.len();
    if n == 0 || n % k1 != 0 {
        return Err(Error::shape(
            "positions",
            format!("expected (K+1)*V = {k1}*V points, got {n}"),
        ));
    }
    let nv = n / k1;
    if !d.positions.iter().all(finite3) {
        return Err(Error::value("positions", "must be finite"));
    }
    if d.positions.iter().flatten().any(|x| x.abs() > 1e15) {
        return Err(Error::value(
            "positions",
            "must lie within 1e15 of the origin",
        ));
    }
    if d.faces.iter().flatten().any(|&i| i as usize >= nv) {
        return Err(Error::value(
            "faces",
            format!("indices must be below the {nv} vertices"),
        ));
    }
    if d.rgba.len() != 1 && d.rgba.len() != nv {
        return Err(Error::shape(
            "rgba",
            format!("expected 1 or {nv} colours, got {}", d.rgba.len()),
        ));
    }
    if d.rgba
        .iter()
        .any(|c| !c.iter().all(|x| x.is_finite()) || c[..3].iter().any(|x| *x < 0.0))
        || d.rgba.iter().any(|c| !(0.0..=1.0).contains(&c[3]))
    {
        return Err(Error::value(
            "rgba",
            "colours must be finite and >= 0, alpha in [0, 1]",
        ));
    }
    if let Some(nm) = d.normals {
        if nm.len() != n {
            return Err(Error::shape(
                "normals",
                format!("expected {n} normals (one per position), got {}", nm.len()),
            ));
        }
        if !nm.iter().flatten().all(|x| x.is_finite()) {
            return Err(Error::value("normals", "must be finite"));
        }
    }
    Ok(())
}

/// The backdrop: one entry per sample of the `input`'s image, depths > 0, colours finite.
fn validate_backdrop(b: &Layer, input: &Input) -> Result<()> {
    let ws = (input.width * input.samples) as usize;
    let hs = (input.height * input.samples) as usize;
    if (b.width, b.height) != (ws, hs) {
        return Err(Error::shape(
            "backdrop",
            format!(
                "expected one entry per sample ({hs}x{ws}), got {}x{}",
                b.height, b.width
            ),
        ));
    }
    b.check_lengths("backdrop")?;
    if b.depth.iter().any(|z| z.is_nan() || *z <= 0.0) || !b.rgba.iter().all(|x| x.is_finite()) {
        return Err(Error::value(
            "backdrop",
            "depth must be > 0 (inf where empty) and colours finite",
        ));
    }
    Ok(())
}

/// With the exposure channel on for `n` objects: every draw's and the backdrop's ids in
/// `-1..n`, each of which has a plane.
fn validate_exposure(input: &Input) -> Result<()> {
    let Some(n) = input.exposure else {
        return Ok(());
    };
    if n == u32::MAX {
        return Err(Error::value("exposure", "too many objects"));
    }
    let fits = |id: i32| id >= -1 && i64::from(id) < i64::from(n);
    if let Some(d) = input.draws.iter().find(|d| !fits(d.object_id)) {
        return Err(Error::value(
            "object_id",
            format!(
                "{} is not an id of the exposure's {n} objects (-1 to {})",
                d.object_id,
                i64::from(n) - 1
            ),
        ));
    }
    if let Some(b) = &input.backdrop {
        if let Some(id) = b.ids.iter().find(|i| !fits(**i)) {
            return Err(Error::value(
                "backdrop",
                format!("id {id} is not an id of the exposure's {n} objects"),
            ));
        }
    }
    Ok(())
}

/// Clip positions (camera of each boundary) and, for lambert shading, normals of one draw:
/// the clip positions of every point computed at once when `dense`, else each when asked (or
/// from a strip's table, [`Prepared::with_table`]).
pub fn prepare<'a>(input: &Input<'a>, d: &MovingDraw<'a>, dense: bool) -> Prepared<'a> {
    let k1 = input.times.len();
    let nv = d.positions.len() / k1;
    let mut p = Prepared {
        nv,
        clip: Clip::Direct,
        positions: d.positions,
        view_projections: input.view_projections,
        normals: Cow::Owned(Vec::new()),
        opaque_everywhere: d.rgba.iter().all(|c| c[3] >= 1.0),
        uniform: uniform_colour(input, d),
    };
    if dense {
        let clip = (0..d.positions.len())
            .into_par_iter()
            .with_min_len(4096)
            .map(|i| p.compute(i / nv, i))
            .collect();
        p.clip = Clip::Dense(clip);
    }
    p.normals = match (d.shading, input.shade, d.normals) {
        (Shading::Lambert, true, Some(n)) => Cow::Borrowed(n),
        (Shading::Lambert, true, None) => Cow::Owned(
            (0..k1)
                .into_par_iter()
                .flat_map_iter(|k| vertex_normals(&d.positions[k * nv..(k + 1) * nv], d.faces))
                .collect(),
        ),
        _ => Cow::Owned(Vec::new()),
    };
    p
}

impl Prepared<'_> {
    /// The clip position of point `i` (of boundary `k`) of the `(K+1) * V`, boundary-major:
    /// its world position seen by the camera of its boundary.
    #[inline]
    fn compute(&self, k: usize, i: usize) -> [f64; 4] {
        let vps = self.view_projections;
        let m = vps[if vps.len() == 1 { 0 } else { k }];
        let p = self.positions[i];
        let c = m * DVec4::new(p[0], p[1], p[2], 1.0);
        [c.x, c.y, c.z, c.w]
    }

    /// The clip position of vertex `v` at boundary `k`, seen by the camera of that boundary
    /// (from a strip's table: a point its triangles use).
    #[inline]
    pub fn clip_at(&self, k: usize, v: usize) -> [f64; 4] {
        let i = k * self.nv + v;
        match &self.clip {
            Clip::Dense(c) => c[i],
            // every point a strip's triangles use is in its table; one that were not is
            // computed here, the same value, rather than read from a neighbour's place
            Clip::Table(t) => t.get(i).unwrap_or_else(|| self.compute(k, i)),
            Clip::Direct => self.compute(k, i),
        }
    }

    /// The points of `marks` (boundary-major indices) computed into a table.
    pub fn table(&self, marks: Marks) -> ClipTable {
        ClipTable::new(marks, |i| self.compute(i / self.nv, i))
    }

    /// This draw reading its clip positions from `table` ([`Prepared::table`]), the rest
    /// borrowed.
    pub fn with_table<'b>(&'b self, table: &'b ClipTable) -> Prepared<'b> {
        Prepared {
            nv: self.nv,
            clip: Clip::Table(table),
            positions: self.positions,
            view_projections: self.view_projections,
            normals: Cow::Borrowed(&self.normals[..]),
            opaque_everywhere: self.opaque_everywhere,
            uniform: self.uniform,
        }
    }
}

/// See [`Prepared::uniform`]: the straight colour premultiplied as shading does.
fn uniform_colour(input: &Input, d: &MovingDraw) -> Option<[f32; 4]> {
    if !input.shade {
        return Some([1.0; 4]);
    }
    let c = d.rgba[0];
    if d.shading == Shading::Lambert || d.rgba.iter().any(|x| *x != c) {
        return None;
    }
    let a = c[3].clamp(0.0, 1.0);
    Some([c[0] * a, c[1] * a, c[2] * a, a])
}
