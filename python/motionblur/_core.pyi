"""Type stubs of the compiled core. The public API wraps these; see the Python modules."""

import numpy as np

__version__: str

# --- geometry (mesh, contour, motion volume, contour table)

# --- end geometry

# --- image (motionblur.image kernels)

def _glow(alpha: np.ndarray, direction: tuple[float, float], width: float) -> np.ndarray:
    """Eq. 10 glow of alpha (H,W) f32 along direction (pixels) with half-width width (pixels).
    Returns (H,W) f32 >= alpha. Releases the GIL."""

def _box_blur(rgba: np.ndarray, direction: tuple[float, float], length: float) -> np.ndarray:
    """Box blur of rgba (H,W,4) f32 over length pixels along direction. Returns (H,W,4) f32."""

def _opaque_blur(rgba: np.ndarray, direction: tuple[float, float], length: float) -> np.ndarray:
    """Box blur, eq. 10 glow and eq. 7 rescale of premultiplied rgba (H,W,4) f32. Returns (H,W,4) f32."""

def _opaque_motion_blur(
    rgba: np.ndarray, base: np.ndarray | None, direction: tuple[float, float], length: float, mode: str
) -> np.ndarray:
    """_opaque_blur composited 'over' or 'under' base (H,W,4) f32 (None: rgba). Returns (H,W,4) f32."""

def _pyramid_blur(rgba: np.ndarray, levels: int) -> np.ndarray:
    """4x4-box analysis, biquadratic B-spline synthesis over levels levels. (H,W,4) f32 in and out."""

def _pyramid_glow(alpha: np.ndarray, levels: int) -> np.ndarray:
    """Pyramid glow (eqs. 8-9) of alpha (H,W) f32. Returns (H,W) f32 >= alpha."""

def _pyramid_opaque_blur(rgba: np.ndarray, levels: int) -> np.ndarray:
    """Pyramid blur rescaled to the pyramid glow (eq. 7). (H,W,4) f32 in and out."""

def _depth_of_field(
    rgba: np.ndarray,
    depth: np.ndarray,
    focal_depth: float,
    focal_length: float,
    f_number: float,
    yfov: float,
    layers: int,
) -> np.ndarray:
    """Sub-image depth of field of rgba (H,W,4) f32 with view-axis depth (H,W) f32 (inf sky);
    focal_depth, focal_length in scene units, yfov radians. Returns (H,W,4) f32."""

def _camera_velocity(
    depth: np.ndarray,
    view: np.ndarray,
    projection: np.ndarray,
    previous_view: np.ndarray,
    previous_projection: np.ndarray,
) -> np.ndarray:
    """Velocity (H,W,2) f32 pixels (current minus previous) of depth (H,W) f32 seen by the camera
    with view/projection (4,4) f64 when it moved from the previous one."""

def _velocity_blur(rgba: np.ndarray, velocity: np.ndarray, samples: int) -> np.ndarray:
    """Centred samples-tap blur of rgba (H,W,4) f32 along velocity (H,W,2) f32 pixels."""

def _camera_motion_blur(
    rgba: np.ndarray,
    depth: np.ndarray,
    view: np.ndarray,
    projection: np.ndarray,
    previous_view: np.ndarray,
    previous_projection: np.ndarray,
    samples: int,
    scale: float,
) -> np.ndarray:
    """Chapman's camera blur: _camera_velocity times scale, then _velocity_blur. (H,W,4) f32."""

# --- end image

# --- shell (blur shells, silhouette of motion)

# --- end shell

# --- raster

def _rasterize(
    view: np.ndarray,
    projection: np.ndarray,
    width: int,
    height: int,
    draws: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None, int, bool, np.ndarray | None]],
    samples: int,
    blend: str,
    shading: str,
    lights: list[tuple[tuple[float, float, float], tuple[float, float, float]]],
    ambient: tuple[float, float, float],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, float]]:
    """Render draws (vertices f64 (V,3), faces i64 (F,3), straight rgba f32 (1|V,4), normals f32
    (V,3) | None, object_id, cull_back, previous_vertices f64 (V,3) | None) seen through view and
    projection (4,4) f64 into an image of height x width. Returns rgba (H,W,4) f32 premultiplied,
    depth (H,W) f32 view-axis distance (inf background), ids (H,W) i32 (-1 background), velocity
    (H,W,2) f32 pixels, and a stats dict. Releases the GIL."""

# --- scenes (accumulation kernels)

def _accumulate(
    acc: np.ndarray, rgba: np.ndarray, depth: np.ndarray, limit: np.ndarray | None, weight: float
) -> None:
    """In place: acc (H,W,4) f32 += weight * rgba (H,W,4) f32 where depth (H,W) f32 < limit (H,W)
    f32 (everywhere when limit is None). All C-contiguous. Releases the GIL."""

def _over(acc: np.ndarray, under: np.ndarray) -> None:
    """In place: acc (H,W,4) f32 += under (H,W,4) f32 * (1 - acc alpha). Releases the GIL."""

# --- end scenes
