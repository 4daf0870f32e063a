"""Type stubs of the compiled core. The public API wraps these; see the Python modules."""

import numpy as np

__version__: str

# --- geometry (mesh, contour, motion volume, contour table)

# --- end geometry

# --- image (motionblur.image kernels)

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
