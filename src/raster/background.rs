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
use crate::frame::Layer;

/// The window of a kept layer a frame starts from: the frame's `ws` x `hs` samples read the
/// samples of `layer` (one entry per sample, `layer.width` a row) whose top-left one is
/// (`x0`, `y0`) ((0, 0) and a layer of exactly the frame's samples for the whole layer), so a
/// window of a kept layer needs no copy. Colours premultiplied and finite, depths > 0 (`inf`
/// where there is no surface).
#[derive(Clone, Copy, Debug)]
pub struct Background<'a> {
    /// The kept layer, one entry per sample.
    pub layer: Layer<'a>,
    /// The layer's sample under the frame's sample (0, 0).
    pub x0: usize,
    /// The layer's row under the frame's sample row 0.
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
        self.layer.check_lengths("background")?;
        let l = &self.layer;
        if self.x0 + ws > l.width || self.y0 + hs > l.height {
            return Err(Error::shape(
                "background",
                format!(
                    "must hold the frame's {hs}x{ws} samples from ({}, {}), got {}x{}",
                    self.y0, self.x0, l.height, l.width
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
            let row = iy * self.layer.width + self.x0;
            bad_depth |= self.layer.depth[row..row + ws]
                .iter()
                .fold(false, |bad, d| bad | bad_depth_bits(*d));
            bad_rgba |= self.layer.rgba[4 * row..4 * (row + ws)]
                .iter()
                .fold(false, |bad, c| bad | bad_colour_bits(*c));
        }
        if bad_depth {
            let d = (self.y0..self.y0 + hs)
                .flat_map(|iy| &self.layer.depth[iy * self.layer.width + self.x0..][..ws])
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
        let i = (iy + self.y0) * self.layer.width + ix + self.x0;
        let c = &self.layer.rgba[4 * i..4 * i + 4];
        Sample {
            rgba: [c[0], c[1], c[2], c[3]],
            invw: 1.0 / self.layer.depth[i],
            id: self.layer.ids[i],
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
            let i = (iy + self.y0) * self.layer.width + x0 + self.x0;
            let z = &mut zbuf[row..row + w];
            for (z, &d) in z.iter_mut().zip(&self.layer.depth[i..i + w]) {
                *z = 1.0 / d;
                bad |= bad_depth_bits(d);
            }
            let rgba = &self.layer.rgba[4 * i..4 * (i + w)];
            bad |= rgba.iter().fold(false, |bad, c| bad | bad_colour_bits(*c));
            let ids = &self.layer.ids[i..i + w];
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
                layer: Layer {
                    width: 2,
                    height: 1,
                    rgba,
                    depth: &depth,
                    ids: &ids,
                },
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
            layer: Layer {
                width: 4,
                height: 3,
                rgba: &rgba,
                depth: &depth,
                ids: &ids,
            },
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
        bg.layer.depth = &outside;
        assert!(bg.validate(2, 2).is_ok());
        let mut inside = depth.clone();
        inside[5] = f32::NAN;
        bg.layer.depth = &inside;
        assert!(bg.validate(2, 2).is_err());
    }
}
