"""Type stubs of the compiled core. The public API wraps these; see the Python modules."""

import numpy as np

__version__: str

# --- geometry (mesh, contour, motion volume, contour table)

LEADING: int
TRAILING: int
JOINING: int

class _Mesh:
    """Rust mesh: owned float64 vertices (V,3), faces (F,3) and the cached edge adjacency."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray) -> None:
        """vertices (V,3) float64 C-contiguous, faces (F,3) int64 with indices in [0, V)."""
    def with_vertices(self, vertices: np.ndarray) -> _Mesh:
        """Same faces and cached adjacency, new (V,3) float64 vertex positions."""
    def has_adjacency(self) -> bool: ...
    def stats(self) -> dict[str, int | bool]:
        """faces, vertices, edges, degenerate_faces, boundary_edges, nonmanifold_edges,
        inconsistent_edges, unreferenced_vertices (int) and closed (bool)."""
    def face_normals(self, unit: bool = True) -> np.ndarray:
        """(F,3) float64 unit face normals (zero if degenerate), or raw (b - a) x (c - a)."""
    def vertex_normals(self) -> np.ndarray:
        """(V,3) float64 area-weighted unit vertex normals (zero where undefined)."""
    def edges(self) -> np.ndarray:
        """(E,2) int64 undirected edges a < b, sorted."""
    def edge_face_counts(self) -> np.ndarray:
        """(E,) int64 number of faces on each edge of edges()."""
    def build_adjacency(self) -> None:
        """Build the edge adjacency now (releases the GIL)."""

def contour_edges(mesh: _Mesh, motion: np.ndarray, camera_position: np.ndarray | None = None) -> np.ndarray:
    """(E,2) int64 oriented contour edges for the (3,) float64 motion; with a (3,) camera
    position, the contour-line subset. Releases the GIL."""

def motion_volume(
    mesh: _Mesh,
    keyframes: np.ndarray,
    segments: int,
    filter: str,
    colors: np.ndarray,
    normals: np.ndarray | None = None,
    camera_position: np.ndarray | None = None,
    face_colors: bool = False,
    contour_line: bool = True,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, int]:
    """Motion volume for keyframes (K+1,4,4) float64, each interval cut into segments, filter
    'ramp' | 'box' | 'triangle' | 'gaussian', colors (1|V,4) float32 straight RGBA (or (F,4)
    per face with face_colors=True), normals
    (V,3) float64 | None, camera_position (3,) float64 | None, contour_line (camera: sweep only the
    contour line; False: the camera sets the alphas only). Returns vertices (N,3) f64,
    faces (M,3) i64, rgba (N,4) f32, normals (N,3) f32, part (M,) u8, ring_alpha (n+1,) f64
    and the number of contour edges. Releases the GIL."""

def spin_volume(
    mesh: _Mesh,
    axis: np.ndarray,
    angle: float,
    center: np.ndarray,
    translation: np.ndarray,
    segments: int | None,
    filter: str,
    colors: np.ndarray,
    normals: np.ndarray | None = None,
    camera_position: np.ndarray | None = None,
    face_colors: bool = False,
    contour_line: bool = True,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, int]:
    """Spin volume (section 4.3): axis (3,) f64, angle radians, center (3,) f64, translation
    (3,) f64, segments (sweep steps) | None; the rest and the result as motion_volume
    (contour_line is ignored: every contour edge is swept).
    Releases the GIL."""

class _ContourTable:
    """Contour sets precomputed for K directions (section 4.4)."""

    def __init__(self, mesh: _Mesh, count: int, seed: int, directions: np.ndarray | None = None) -> None:
        """count random directions from seed (splitmix64), or the given (K,3) float64 ones."""
    def __len__(self) -> int: ...
    def directions(self) -> np.ndarray:
        """(K,3) float64 unit directions."""
    def nearest(self, motion: np.ndarray) -> tuple[int, float]:
        """(index, angle in radians) of the stored direction nearest to the (3,) motion."""
    def edges(self, index: int) -> np.ndarray:
        """(E,2) int64 contour edges stored for direction index."""
    def front(self, index: int) -> np.ndarray:
        """(F,) bool front faces stored for direction index."""
    def storage_bytes(self) -> int: ...

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
