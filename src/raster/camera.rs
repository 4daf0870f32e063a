//! The camera as the rasterizer sees it: a view and a projection matrix and an image size.
//!
//! OpenGL and pyrender conventions: the pose is camera-to-world, the camera looks down its -Z with
//! +Y up, `yfov` is the vertical field of view in radians, pixel centres sit at +0.5. The
//! projection equals pyrender's `PerspectiveCamera.get_projection_matrix` (an infinite far plane
//! when `zfar` is infinite).
use crate::error::{Error, Result};
use glam::{DMat4, DVec4};

/// Largest image side accepted, in pixels.
pub const MAX_SIDE: u32 = 16384;
/// Largest pixel count accepted (the frame's buffers take 32 bytes a pixel: 1 GiB at this size).
pub const MAX_PIXELS: u64 = 1 << 25;
/// Largest side of the supersampled (internal) image: keeps fixed-point coordinates in range.
pub const MAX_INTERNAL_SIDE: u32 = 32768;
/// Samples per pixel along each axis the rasterizer takes.
pub const SAMPLES: [u32; 3] = [1, 2, 4];

/// A perspective camera: matrices in f64, image size in pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// World-to-camera transform.
    pub view: DMat4,
    /// Camera-to-clip transform (OpenGL clip space, w = distance along the view axis).
    pub projection: DMat4,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

/// pyrender's perspective projection: `aspect` is width / height, `zfar` may be infinite.
pub fn perspective(yfov: f64, aspect: f64, znear: f64, zfar: f64) -> DMat4 {
    let t = (yfov / 2.0).tan();
    let (p22, p23) = if zfar.is_infinite() {
        (-1.0, -2.0 * znear)
    } else {
        (
            (zfar + znear) / (znear - zfar),
            2.0 * zfar * znear / (znear - zfar),
        )
    };
    // Columns of the row-major matrix [[1/(a t),0,0,0],[0,1/t,0,0],[0,0,p22,p23],[0,0,-1,0]].
    DMat4::from_cols(
        DVec4::new(1.0 / (aspect * t), 0.0, 0.0, 0.0),
        DVec4::new(0.0, 1.0 / t, 0.0, 0.0),
        DVec4::new(0.0, 0.0, p22, -1.0),
        DVec4::new(0.0, 0.0, p23, 0.0),
    )
}

/// Camera-to-world pose at `eye` looking at `target` (the camera's -Z points at the target).
#[cfg(test)]
pub(crate) fn look_at(eye: glam::DVec3, target: glam::DVec3, up: glam::DVec3) -> Result<DMat4> {
    let back = eye - target;
    if back.length() == 0.0 || !back.is_finite() {
        return Err(Error::value("target", "must differ from eye"));
    }
    let z = back.normalize();
    let x = up.cross(z);
    if x.length() < 1e-12 * up.length().max(1e-300) || !x.is_finite() {
        return Err(Error::value(
            "up",
            "must not be parallel to the view direction",
        ));
    }
    let x = x.normalize();
    let y = z.cross(x);
    Ok(DMat4::from_cols(
        x.extend(0.0),
        y.extend(0.0),
        z.extend(0.0),
        eye.extend(1.0),
    ))
}

/// Checks an image size: both sides in 1..=MAX_SIDE and the pixel count within MAX_PIXELS.
pub fn check_size(width: u32, height: u32, samples: u32) -> Result<()> {
    for (name, v) in [("width", width), ("height", height)] {
        if v == 0 || v > MAX_SIDE {
            return Err(Error::value(
                name,
                format!("must be in 1..={MAX_SIDE}, got {v}"),
            ));
        }
    }
    if u64::from(width) * u64::from(height) > MAX_PIXELS {
        return Err(Error::value(
            "width",
            format!("width * height must be <= {MAX_PIXELS}, got {width} x {height}"),
        ));
    }
    if !SAMPLES.contains(&samples) {
        return Err(Error::value(
            "samples",
            format!("must be 1, 2 or 4, got {samples}"),
        ));
    }
    if width * samples > MAX_INTERNAL_SIDE || height * samples > MAX_INTERNAL_SIDE {
        return Err(Error::value(
            "samples",
            format!("width and height times samples must be <= {MAX_INTERNAL_SIDE}"),
        ));
    }
    Ok(())
}

impl Camera {
    /// A camera from a camera-to-world `pose`, checked like the Python constructor.
    pub fn new(
        pose: DMat4,
        yfov: f64,
        width: u32,
        height: u32,
        znear: f64,
        zfar: f64,
    ) -> Result<Self> {
        if !pose.is_finite() {
            return Err(Error::value("pose", "contains NaN or inf"));
        }
        if !(yfov > 0.0 && yfov < std::f64::consts::PI) {
            return Err(Error::value(
                "yfov",
                format!("must be in (0, pi), got {yfov}"),
            ));
        }
        if !(znear > 0.0 && znear.is_finite()) {
            return Err(Error::value("znear", format!("must be > 0, got {znear}")));
        }
        if !(zfar > znear) {
            return Err(Error::value("zfar", format!("must be > znear, got {zfar}")));
        }
        check_size(width, height, 1)?;
        if pose.determinant().abs() < 1e-300 {
            return Err(Error::value("pose", "is singular"));
        }
        let aspect = f64::from(width) / f64::from(height);
        Ok(Camera {
            view: pose.inverse(),
            projection: perspective(yfov, aspect, znear, zfar),
            width,
            height,
        })
    }

    /// A camera from explicit matrices (as the binding passes them), checked.
    pub fn from_matrices(view: DMat4, projection: DMat4, width: u32, height: u32) -> Result<Self> {
        if !view.is_finite() {
            return Err(Error::value("camera", "view matrix contains NaN or inf"));
        }
        if !projection.is_finite() {
            return Err(Error::value(
                "camera",
                "projection matrix contains NaN or inf",
            ));
        }
        check_size(width, height, 1)?;
        Ok(Camera {
            view,
            projection,
            width,
            height,
        })
    }

    /// World-to-clip transform.
    pub fn view_projection(&self) -> DMat4 {
        self.projection * self.view
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn look_at_points_minus_z_at_the_target() {
        let pose = look_at(DVec3::new(1.0, 2.0, 3.0), DVec3::ZERO, DVec3::Y).unwrap();
        let forward = -pose.z_axis.truncate();
        let want = (DVec3::ZERO - DVec3::new(1.0, 2.0, 3.0)).normalize();
        assert!((forward - want).length() < 1e-12);
        assert!(pose.y_axis.y > 0.0);
    }

    #[test]
    fn projection_maps_near_and_far_to_minus_one_and_one() {
        let p = perspective(0.8, 1.5, 0.1, 50.0);
        let near = p * DVec4::new(0.0, 0.0, -0.1, 1.0);
        let far = p * DVec4::new(0.0, 0.0, -50.0, 1.0);
        assert!((near.z / near.w + 1.0).abs() < 1e-12);
        assert!((far.z / far.w - 1.0).abs() < 1e-12);
        assert!((near.w - 0.1).abs() < 1e-15);
    }

    #[test]
    fn bad_cameras_name_the_argument() {
        let e = Camera::new(DMat4::IDENTITY, 1.0, 0, 10, 0.1, 10.0).unwrap_err();
        assert!(e.to_string().starts_with("width"));
        let e = Camera::new(DMat4::IDENTITY, 1.0, 10, 10, 0.0, 10.0).unwrap_err();
        assert!(e.to_string().starts_with("znear"));
        let e = Camera::new(DMat4::IDENTITY, 1.0, 16384, 16384, 0.1, 10.0).unwrap_err();
        assert!(e.to_string().starts_with("width"));
        assert!(check_size(10, 10, 3).is_err());
    }
}
