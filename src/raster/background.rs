//! An opaque layer a frame starts from, one entry per sample.
//!
//! A caller that already holds the opaque part of a frame (a static layer kept across frames)
//! passes it as the background: every sample starts with its colour, and its depth pre-loads the
//! z-buffer, so the frame's draws are depth-tested against it exactly as if the opaque surfaces
//! had been drawn first, and transparent fragments in front of it are composited over its
//! colour. Only the new draws are rasterized. The result equals drawing the opaque surfaces in
//! the same pass, except when a fragment lies within one float ulp of the background's depth
//! (the background holds depth = 1/(1/w) rounded, not 1/w itself): coplanar surfaces fight
//! either way.
use super::blend::Sample;
use super::tile::TILE;
use crate::{Error, Result};

/// Per-sample arrays of the background, row-major, `width * samples` x `height * samples`.
#[derive(Clone, Copy, Debug)]
pub struct Background<'a> {
    /// Premultiplied linear RGBA, 4 floats a sample, finite.
    pub rgba: &'a [f32],
    /// View-axis distance of the opaque surface, > 0; `inf` where there is none.
    pub depth: &'a [f32],
    /// Object id of that surface (-1 where there is none).
    pub ids: &'a [i32],
    /// Samples per row (`width * samples`).
    pub stride: usize,
}

impl Background<'_> {
    /// Checks the lengths against a `ws` x `hs`-sample frame and the values.
    pub fn validate(&self, ws: usize, hs: usize) -> Result<()> {
        let n = ws * hs;
        if self.stride != ws || self.depth.len() != n {
            return Err(Error::shape(
                "background",
                format!(
                    "depth must hold one value per sample ({hs}x{ws}), got {} values in rows of {}",
                    self.depth.len(),
                    self.stride
                ),
            ));
        }
        if self.rgba.len() != 4 * n || self.ids.len() != n {
            return Err(Error::shape(
                "background",
                format!(
                    "rgba must be ({hs},{ws},4) and ids ({hs},{ws}), got {} and {} values",
                    self.rgba.len(),
                    self.ids.len()
                ),
            ));
        }
        if let Some(d) = self.depth.iter().find(|d| !(**d > 0.0)) {
            return Err(Error::value(
                "background",
                format!("depth must be > 0 (inf where empty), got {d}"),
            ));
        }
        if self.rgba.iter().any(|c| !c.is_finite()) {
            return Err(Error::value("background", "rgba contains NaN or inf"));
        }
        Ok(())
    }

    /// The sample at (ix, iy) as the opaque pass would leave it.
    #[inline]
    pub fn sample(&self, ix: usize, iy: usize) -> Sample {
        let i = iy * self.stride + ix;
        let c = &self.rgba[4 * i..4 * i + 4];
        Sample {
            rgba: [c[0], c[1], c[2], c[3]],
            invw: 1.0 / self.depth[i],
            id: self.ids[i],
            velocity: [0.0; 2],
        }
    }

    /// Loads the samples `rect` = [x0, y0, x1, y1) into a tile's buffers (row stride TILE):
    /// `samples` gets the background, `zbuf` its 1/w (0 where empty).
    pub fn load(&self, rect: [i32; 4], zbuf: &mut [f32], samples: &mut [Sample]) {
        let [x0, y0, x1, y1] = rect.map(|v| v as usize);
        for iy in y0..y1 {
            let row = (iy - y0) * TILE as usize;
            for ix in x0..x1 {
                let s = self.sample(ix, iy);
                zbuf[row + ix - x0] = s.invw;
                samples[row + ix - x0] = s;
            }
        }
    }
}
