//! Options of one frame: shading, lights, blending, and their parsing from names.
use crate::error::{Error, Result};

/// How transparent fragments are composited.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Blend {
    /// Sorted by depth per sample, composited back to front.
    Exact,
    /// Composited in submission order, as unsorted z-buffer hardware does.
    Unsorted,
}

/// How fragments are shaded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shading {
    /// Unlit: the colour itself.
    Flat,
    /// Ambient plus Lambert's cosine per directional light.
    Lambert,
}

/// A directional light: `direction` is the way the light travels (normalised by `Options::new`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Unit direction the light travels.
    pub direction: [f32; 3],
    /// RGB intensity.
    pub intensity: [f32; 3],
}

/// Options of one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Samples per pixel along each axis: 1, 2 or 4.
    pub samples: u32,
    /// How transparent fragments are composited.
    pub blend: Blend,
    /// How fragments are shaded.
    pub shading: Shading,
    /// Directional lights of lambert shading.
    pub lights: Vec<Light>,
    /// Ambient RGB of lambert shading.
    pub ambient: [f32; 3],
}

impl Default for Options {
    fn default() -> Self {
        Options {
            samples: 1,
            blend: Blend::Exact,
            shading: Shading::Flat,
            lights: Vec::new(),
            ambient: [0.0; 3],
        }
    }
}

impl Blend {
    /// The blend modes' names, as [`Blend::parse`] takes them.
    pub const NAMES: [&'static str; 2] = ["exact", "unsorted"];

    /// "exact" or "unsorted".
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "exact" => Ok(Blend::Exact),
            "unsorted" => Ok(Blend::Unsorted),
            _ => Err(Error::value(
                "blend",
                format!("expected 'exact' or 'unsorted', got {name:?}"),
            )),
        }
    }
}

impl Shading {
    /// The shading modes' names, as [`Shading::parse`] takes them.
    pub const NAMES: [&'static str; 2] = ["flat", "lambert"];

    /// "flat" or "lambert".
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "flat" => Ok(Shading::Flat),
            "lambert" => Ok(Shading::Lambert),
            _ => Err(Error::value(
                "shading",
                format!("expected 'flat' or 'lambert', got {name:?}"),
            )),
        }
    }
}

impl Light {
    /// A light travelling along `direction` (any non-zero length) with RGB `intensity`.
    pub fn new(direction: [f64; 3], intensity: [f64; 3]) -> Result<Self> {
        let l = (direction[0] * direction[0]
            + direction[1] * direction[1]
            + direction[2] * direction[2])
            .sqrt();
        if !(l > 0.0 && l.is_finite()) {
            return Err(Error::value(
                "lights",
                "direction must be finite and non-zero",
            ));
        }
        if intensity.iter().any(|x| !x.is_finite() || *x < 0.0) {
            return Err(Error::value("lights", "intensity must be finite and >= 0"));
        }
        Ok(Light {
            direction: direction.map(|d| (d / l) as f32),
            intensity: intensity.map(|x| x as f32),
        })
    }
}

/// Checks the options that the types do not already guarantee.
pub fn check_options(o: &Options) -> Result<()> {
    if o.ambient.iter().any(|x| !x.is_finite() || *x < 0.0) {
        return Err(Error::value("ambient", "must be finite and >= 0"));
    }
    Ok(())
}
