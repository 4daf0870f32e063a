"""Type stubs of the compiled core. The public API wraps these; see the Python modules."""

import numpy as np

__version__: str

# --- geometry (mesh, contour, motion volume, contour table)

# --- end geometry

# --- image (motionblur.image kernels)

# --- end image

# --- shell (blur shells, silhouette of motion)

class _BlurShell:
    """Rust blur shell (see motionblur.BlurShell). faces i64 (F,3); mask bool (F,) | None; color
    f32 (1,3) | (V,3) | None (white)."""

    def __init__(
        self,
        faces: np.ndarray,
        n_vertices: int,
        subdivisions: int,
        hysteresis: int,
        initial_alpha: float,
        mask: np.ndarray | None = None,
        color: np.ndarray | None = None,
    ) -> None: ...
    def update(self, vertices: np.ndarray, normals: np.ndarray | None = None) -> None:
        """vertices, normals f64 (V,3) C-contiguous. Releases the GIL."""
    def build(
        self, vertices: np.ndarray | None = None, normals: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(vertices f64 (N,3), faces i64 (M,3), rgba f32 (N,4) straight, normals f32 (N,3),
        face i64 (N,), step i32 (N,)). Releases the GIL."""
    def reset(self) -> None: ...
    @property
    def updates(self) -> int: ...
    @property
    def update_index(self) -> int | None: ...
    @property
    def n_vertices(self) -> int: ...
    @property
    def n_faces(self) -> int: ...
    def _state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(facing i8 (V,), last edge i8 (F,), since i64 (F,), fade i32 (F,), run i32 (F,))."""
    def _element(self, face: int, age: int) -> tuple[int, bool] | None: ...

def _motion_silhouette(
    vertices: np.ndarray, previous_vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(facing i8 (V,) +1/-1/0, edge i8 (F,) k or -1). f64 (V,3) inputs, faces i64 (F,3)."""

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
