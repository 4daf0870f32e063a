//! Typed arguments several bindings share, read by `#[derive(FromPyObject)]`: a layer of
//! samples (read off any object with `rgba`, `depth` and `ids` attributes: a `Frame`, the
//! methods' `Layer`), lights, and the (4,4) matrices. Extraction only converts types; shapes and
//! ranges are checked after it (here for shapes, by the core for values), so every error names
//! the Python argument.
use numpy::PyUntypedArrayMethods;
use numpy::{PyReadonlyArray2, PyReadonlyArray3, PyReadwriteArray2, PyReadwriteArray3};
use pyo3::prelude::*;

use super::convert::{c_slice, c_slice_mut};
use crate::{Error, Layer, Light};

/// A layer of samples as the Python layer has it: the attributes `rgba` (H,W,4) float32,
/// `depth` (H,W) float32 and `ids` (H,W) int32 of any object, read-only.
#[derive(FromPyObject)]
pub(crate) struct LayerArg<'py> {
    pub rgba: PyReadonlyArray3<'py, f32>,
    pub depth: PyReadonlyArray2<'py, f32>,
    pub ids: PyReadonlyArray2<'py, i32>,
}

/// The data of a layer, C order: (rgba, depth, ids).
pub(crate) type Planes<'a> = (&'a [f32], &'a [f32], &'a [i32]);

impl LayerArg<'_> {
    /// Its (rows, columns) after checking that rgba, depth and ids agree; errors name `name`.
    pub fn size(&self, name: &'static str) -> Result<[usize; 2], Error> {
        let [rows, cols] = [self.depth.shape()[0], self.depth.shape()[1]];
        if self.rgba.shape() != [rows, cols, 4] || self.ids.shape() != [rows, cols] {
            return Err(Error::shape(
                name,
                format!(
                    "rgba (R,S,4) and ids (R,S) must match depth {:?}, got {:?} and {:?}",
                    self.depth.shape(),
                    self.rgba.shape(),
                    self.ids.shape()
                ),
            ));
        }
        Ok([rows, cols])
    }

    /// Its data in C order, or an error naming `name`.
    pub fn planes(&self, name: &'static str) -> Result<Planes<'_>, Error> {
        Ok((
            c_slice(&self.rgba, name)?,
            c_slice(&self.depth, name)?,
            c_slice(&self.ids, name)?,
        ))
    }

    /// The core's borrowed [`Layer`] of it after the checks of [`Self::size`] and
    /// [`Self::planes`]; errors name `name`.
    pub fn layer(&self, name: &'static str) -> Result<Layer<'_>, Error> {
        let [height, width] = self.size(name)?;
        let (rgba, depth, ids) = self.planes(name)?;
        Ok(Layer {
            width,
            height,
            rgba,
            depth,
            ids,
        })
    }
}

/// A layer written in place: the attributes `rgba`, `depth`, `ids` as [`LayerArg`], writable.
#[derive(FromPyObject)]
pub(crate) struct LayerMutArg<'py> {
    pub rgba: PyReadwriteArray3<'py, f32>,
    pub depth: PyReadwriteArray2<'py, f32>,
    pub ids: PyReadwriteArray2<'py, i32>,
}

/// The mutable data of a layer, C order: (rgba, depth, ids).
pub(crate) type PlanesMut<'a> = (&'a mut [f32], &'a mut [f32], &'a mut [i32]);

impl LayerMutArg<'_> {
    /// Its (rows, columns) after checking that rgba, depth and ids agree; errors name `name`.
    pub fn size(&self, name: &'static str) -> Result<[usize; 2], Error> {
        let [rows, cols] = [self.depth.shape()[0], self.depth.shape()[1]];
        if self.rgba.shape() != [rows, cols, 4] || self.ids.shape() != [rows, cols] {
            return Err(Error::shape(
                name,
                "rgba (H,W,4), depth and ids (H,W) expected",
            ));
        }
        Ok([rows, cols])
    }

    /// Its data in C order, or an error naming `name`.
    pub fn planes(&mut self, name: &'static str) -> Result<PlanesMut<'_>, Error> {
        Ok((
            c_slice_mut(&mut self.rgba, name)?,
            c_slice_mut(&mut self.depth, name)?,
            c_slice_mut(&mut self.ids, name)?,
        ))
    }
}

/// One light as the Python layer passes it: (direction (3,), RGB intensity (3,)).
pub(crate) type LightArg = ([f64; 3], [f64; 3]);

/// The core's lights, checked by [`Light::new`].
pub(crate) fn lights(lights: &[LightArg]) -> Result<Vec<Light>, Error> {
    lights.iter().map(|(d, i)| Light::new(*d, *i)).collect()
}
