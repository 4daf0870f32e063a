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
use super::bins::TILE;
use super::blend::Sample;
use crate::error::{Error, Result};

/// Per-sample arrays of the background, row-major with `stride` samples a row. The frame's
/// `ws` x `hs` samples read the window of these arrays whose top-left sample is (`x0`, `y0`)
/// (0, 0 and `stride` = `ws` for arrays of exactly the frame's samples), so a window of a kept
/// layer needs no copy.
#[derive(Clone, Copy, Debug)]
pub struct Background<'a> {
    /// Premultiplied linear RGBA, 4 floats a sample, finite.
    pub rgba: &'a [f32],
    /// View-axis distance of the opaque surface, > 0; `inf` where there is none.
    pub depth: &'a [f32],
    /// Object id of that surface (-1 where there is none).
    pub ids: &'a [i32],
    /// Samples per row of the arrays.
    pub stride: usize,
    /// The arrays' sample under the frame's sample (0, 0).
    pub x0: usize,
    /// The arrays' row under the frame's sample row 0.
    pub y0: usize,
}

impl Background<'_> {
    /// Checks the lengths against a `ws` x `hs`-sample frame and the values in its window.
    pub fn validate(&self, ws: usize, hs: usize) -> Result<()> {
        self.validate_shape(ws, hs)?;
        self.validate_values(ws, hs)
    }

    /// Checks the lengths against a `ws` x `hs`-sample frame (the values are left to `load`,
    /// which reports bad ones of the samples it reads, and to `validate_values`).
    pub fn validate_shape(&self, ws: usize, hs: usize) -> Result<()> {
        let rows = self.depth.len().checked_div(self.stride).unwrap_or(0);
        if self.stride * rows != self.depth.len()
            || self.x0 + ws > self.stride
            || self.y0 + hs > rows
        {
            return Err(Error::shape(
                "background",
                format!(
                    "depth must hold the frame's {hs}x{ws} samples from ({}, {}), got {} values in rows of {}",
                    self.y0,
                    self.x0,
                    self.depth.len(),
                    self.stride
                ),
            ));
        }
        if self.rgba.len() != 4 * self.depth.len() || self.ids.len() != self.depth.len() {
            return Err(Error::shape(
                "background",
                format!(
                    "rgba must be ({rows},{s},4) and ids ({rows},{s}) like depth, got {} and {} values",
                    self.rgba.len(),
                    self.ids.len(),
                    s = self.stride
                ),
            ));
        }
        Ok(())
    }

    /// Checks the values in the window of a `ws` x `hs`-sample frame (lengths already checked).
    pub fn validate_values(&self, ws: usize, hs: usize) -> Result<()> {
        // Branch-free integer tests over the bits (they vectorize; the arrays are a frame big):
        // a depth d > 0, inf included, has bits in [1, 0x7f80_0000]; NaN and inf have all
        // exponent bits set.
        let (mut bad_depth, mut bad_rgba) = (false, false);
        for iy in self.y0..self.y0 + hs {
            let row = iy * self.stride + self.x0;
            bad_depth |= self.depth[row..row + ws]
                .iter()
                .fold(false, |bad, d| bad | bad_depth_bits(*d));
            bad_rgba |= self.rgba[4 * row..4 * (row + ws)]
                .iter()
                .fold(false, |bad, c| bad | bad_colour_bits(*c));
        }
        if bad_depth {
            let d = (self.y0..self.y0 + hs)
                .flat_map(|iy| &self.depth[iy * self.stride + self.x0..][..ws])
                .find(|d| !(**d > 0.0))
                .expect("one is bad");
            return Err(Error::value(
                "background",
                format!("depth must be > 0 (inf where empty), got {d}"),
            ));
        }
        if bad_rgba {
            return Err(Error::value("background", "rgba contains NaN or inf"));
        }
        Ok(())
    }

    /// The sample under the frame's sample (ix, iy) as the opaque pass would leave it.
    #[inline]
    pub fn sample(&self, ix: usize, iy: usize) -> Sample {
        let i = (iy + self.y0) * self.stride + ix + self.x0;
        let c = &self.rgba[4 * i..4 * i + 4];
        Sample {
            rgba: [c[0], c[1], c[2], c[3]],
            invw: 1.0 / self.depth[i],
            id: self.ids[i],
            velocity: [0.0; 2],
        }
    }

    /// Loads the frame's samples `rect` = [x0, y0, x1, y1) into a tile's buffers (row stride
    /// TILE): `samples` gets the background, `zbuf` its 1/w (0 where empty), as `sample` gives
    /// them. Returns true when one of these samples holds a value `validate_values` rejects
    /// (a depth not > 0, a colour NaN or inf); the frame is then an error.
    pub fn load(&self, rect: [i32; 4], zbuf: &mut [f32], samples: &mut [Sample]) -> bool {
        let [x0, y0, x1, y1] = rect.map(|v| v as usize);
        let w = x1 - x0;
        let mut bad = false;
        for iy in y0..y1 {
            let row = (iy - y0) * TILE as usize;
            let i = (iy + self.y0) * self.stride + x0 + self.x0;
            let z = &mut zbuf[row..row + w];
            for (z, &d) in z.iter_mut().zip(&self.depth[i..i + w]) {
                *z = 1.0 / d;
                bad |= bad_depth_bits(d);
            }
            let rgba = &self.rgba[4 * i..4 * (i + w)];
            bad |= rgba.iter().fold(false, |bad, c| bad | bad_colour_bits(*c));
            let ids = &self.ids[i..i + w];
            for (((smp, c), &id), &invw) in samples[row..row + w]
                .iter_mut()
                .zip(rgba.chunks_exact(4))
                .zip(ids)
                .zip(&*z)
            {
                *smp = Sample {
                    rgba: [c[0], c[1], c[2], c[3]],
                    invw,
                    id,
                    velocity: [0.0; 2],
                };
            }
        }
        bad
    }
}

/// A depth d > 0 (inf included) has bits in [1, 0x7f80_0000]; anything else is bad.
#[inline(always)]
fn bad_depth_bits(d: f32) -> bool {
    d.to_bits().wrapping_sub(1) >= 0x7f80_0000
}

/// NaN and inf have all exponent bits set.
#[inline(always)]
fn bad_colour_bits(c: f32) -> bool {
    c.to_bits() & 0x7f80_0000 == 0x7f80_0000
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validation_accepts_positive_depths_and_finite_colours_only() {
        let rgba = [0.5f32; 8];
        let ids = [0i32; 2];
        let check = |depth: [f32; 2], rgba: &[f32]| {
            Background {
                rgba,
                depth: &depth,
                ids: &ids,
                stride: 2,
                x0: 0,
                y0: 0,
            }
            .validate(2, 1)
        };
        for good in [1.0, f32::INFINITY, f32::MIN_POSITIVE, 1e-45, f32::MAX] {
            assert!(check([good, 2.0], &rgba).is_ok(), "{good}");
        }
        for bad in [
            0.0,
            -0.0,
            -1.0,
            f32::NAN,
            -f32::NAN,
            f32::NEG_INFINITY,
            -1e-45,
        ] {
            assert!(check([2.0, bad], &rgba).is_err(), "{bad}");
        }
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            let mut c = rgba;
            c[5] = bad;
            assert!(check([1.0, 1.0], &c).is_err(), "{bad}");
        }
        assert!(check([1.0, 1.0], &rgba[..4]).is_err(), "short rgba");
    }

    #[test]
    fn a_window_reads_its_samples_and_checks_only_them() {
        // 3 x 4 samples; the frame is the 2 x 2 window from (x0, y0) = (1, 1)
        let depth: Vec<f32> = (0..12).map(|i| 1.0 + i as f32).collect();
        let rgba: Vec<f32> = (0..48).map(|i| i as f32).collect();
        let ids: Vec<i32> = (0..12).collect();
        let mut bg = Background {
            rgba: &rgba,
            depth: &depth,
            ids: &ids,
            stride: 4,
            x0: 1,
            y0: 1,
        };
        assert!(bg.validate(2, 2).is_ok());
        let s = bg.sample(1, 1); // array sample (2, 2): index 10
        assert_eq!((s.id, s.invw, s.rgba[0]), (10, 1.0 / 11.0, 40.0));
        assert!(
            bg.validate(3, 2).is_ok() && bg.validate(4, 2).is_err(),
            "x0 + ws > stride"
        );
        assert!(bg.validate(2, 3).is_err(), "y0 + hs > rows");
        let mut outside = depth.clone();
        outside[0] = f32::NAN; // outside the window: not read, not checked
        bg.depth = &outside;
        assert!(bg.validate(2, 2).is_ok());
        let mut inside = depth.clone();
        inside[5] = f32::NAN;
        bg.depth = &inside;
        assert!(bg.validate(2, 2).is_err());
    }
}
