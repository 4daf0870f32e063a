"""Type stubs of the compiled core. The public API wraps these; see the Python modules."""

from typing import Literal, Protocol, TypedDict, final

import numpy as np
from typing_extensions import NotRequired, Self

# The compiled classes are PyO3 classes: built by __new__ (they have no __init__) and final.

# The typed arguments the core reads (src/python/*.rs, `#[derive(FromPyObject)]`): objects
# whose attributes it reads (Protocols) and dicts whose items it reads (TypedDicts). Private:
# they exist only in these stubs.

_Light = tuple[tuple[float, float, float], tuple[float, float, float]]

class _LayerLike(Protocol):
    """rgba (H,W,4) f32, depth (H,W) f32, ids (H,W) i32, C-contiguous (a Frame, a Layer)."""

    rgba: np.ndarray
    depth: np.ndarray
    ids: np.ndarray

class _CameraLike(Protocol):
    """view and projection (4,4) f64, C-contiguous (a motionblur.Camera)."""

    view: np.ndarray
    projection: np.ndarray

class _DrawLike(Protocol):
    """A motionblur.Draw: vertices f64 (V,3), faces i64 (F,3), straight rgba f32 (1|V,4),
    normals f32 (V,3) | None, object_id, cull_back, previous_vertices f64 (V,3) | None."""

    vertices: np.ndarray
    faces: np.ndarray
    rgba: np.ndarray
    normals: np.ndarray | None
    object_id: int
    cull_back: bool
    previous_vertices: np.ndarray | None

class _MovingDrawLike(Protocol):
    """A motionblur.MovingDraw: positions f64 (K+1,V,3), faces i64 (F,3), straight rgba f32
    (1|V,4), normals f32 (K+1,V,3) | None, object_id, cull_back, shading "flat" | "lambert"."""

    positions: np.ndarray
    faces: np.ndarray
    rgba: np.ndarray
    normals: np.ndarray | None
    object_id: int
    cull_back: bool
    shading: str

class _RasterOptions(TypedDict):
    view: np.ndarray
    projection: np.ndarray
    width: int
    height: int
    samples: int
    blend: str
    shading: str
    lights: list[_Light]
    ambient: tuple[float, float, float]
    origin: tuple[int, int]

class _AnalyticOptions(TypedDict):
    width: int
    height: int
    samples: int
    times: np.ndarray
    view_projections: np.ndarray
    shutter: str | np.ndarray
    lights: list[_Light]
    ambient: tuple[float, float, float]
    gauss: int | Literal["auto"]
    reference_time: float
    shade: bool
    tile_budget: int
    exposure: NotRequired[int | None]

class _VolumeOptions(TypedDict, total=False):
    filter: str
    colors: np.ndarray
    face_colors: bool
    normals: np.ndarray | None
    camera_position: np.ndarray | None
    contour_line: bool
    visible_only: bool
    contour_table: _ContourTable | None
    window: tuple[float, float] | None

class _Spin(TypedDict):
    axis: np.ndarray
    angle: float
    center: np.ndarray
    translation: np.ndarray
    segments: int | None

class _DofOptions(TypedDict):
    focal_depth: float
    focal_length: float
    f_number: float
    yfov: float
    layers: int

class _CameraFrameOptions(TypedDict):
    camera: _CameraLike
    previous_camera: _CameraLike
    scale: float
    samples: int | None

class _ShellOptions(TypedDict):
    subdivisions: int
    hysteresis: int
    initial_alpha: float

class _PaintObject(TypedDict):
    id: int
    shading: str
    vertices: np.ndarray
    faces: np.ndarray
    rgba: np.ndarray
    normals: np.ndarray | None
    keyframes: _Keyframes | None

class _Samples(TypedDict):
    times: np.ndarray
    weights: np.ndarray
    reference: int

class _Piece(TypedDict):
    rgba: np.ndarray
    depth: np.ndarray
    ids: np.ndarray
    ray: tuple[float, float, float, float]
    weight: float
    objects: np.ndarray
    maps: np.ndarray

class _StillCamera(TypedDict):
    view: np.ndarray
    projection: np.ndarray
    view_projection: np.ndarray
    width: int
    height: int
    aa: int

__all__ = [
    "__version__",
    "memory_budget",
    "set_memory_budget",
    "get_num_threads",
    "set_num_threads",
    "MAX_THREADS",
    "_set_simd",
    "_simd_enabled",
    "DEFAULT_MEMORY_BUDGET",
    "MIN_MEMORY_BUDGET",
    "_Keyframes",
    "_check_times",
    "_rotate",
    "MAX_SEGMENTS",
    "MAX_COORD",
    "FILTERS",
    "MAX_SIDE",
    "MAX_PIXELS",
    "FRAGMENT_CAP",
    "MAX_INTERNAL_SIDE",
    "SAMPLES",
    "SHADINGS",
    "BLENDS",
    "MAX_LENGTH",
    "MAX_FPS_RATIO",
    "MAX_VELOCITY",
    "MAX_LEVELS",
    "MAX_LAYERS",
    "MAX_LENS_LEVELS",
    "MAX_SAMPLES",
    "MAX_TAPS",
    "MIN_ALPHA",
    "MAX_SUBDIVISIONS",
    "MAX_HYSTERESIS",
    "_Mesh",
    "_ContourTable",
    "contour_edges",
    "motion_volume",
    "spin_volume",
    "LEADING",
    "TRAILING",
    "JOINING",
    "_rasterize",
    "_on_sample_grid",
    "_analytic",
    "_transform_points",
    "_glow",
    "_box_blur",
    "_coverage_composite",
    "_coverage_blur",
    "_object_pixels",
    "_one_velocity_group",
    "_splat_paths",
    "_scatter_pieces",
    "_pixel_bounds",
    "_sample_colors",
    "_colored",
    "_opaque_blur",
    "_opaque_motion_blur",
    "_pyramid_blur",
    "_pyramid_glow",
    "_pyramid_opaque_blur",
    "_depth_of_field",
    "_lens_blur",
    "_camera_velocity",
    "_velocity_blur",
    "_camera_motion_blur",
    "_reconstruct",
    "_max_speed",
    "_camera_frame_blur",
    "_BlurShell",
    "_motion_silhouette",
    "_resolve",
    "_composite",
    "_accumulate",
    "_over",
    "_facing_faces",
    "_halves",
    "_Painter",
]

__version__: str

# --- the memory budget (src/budget.rs)

DEFAULT_MEMORY_BUDGET: int
MIN_MEMORY_BUDGET: int

def memory_budget() -> int:
    """The most bytes one call may allocate."""

def set_memory_budget(bytes: int) -> int:
    """Sets the memory budget (bytes, >= MIN_MEMORY_BUDGET); returns the previous one."""

# --- the thread pool of the parallel kernels (src/threads.rs)

MAX_THREADS: int

def get_num_threads() -> int:
    """The number of threads the parallel kernels of this process run on (the first call reads
    MOTIONBLUR_NUM_THREADS unless set_num_threads was called)."""

def set_num_threads(n: int) -> int:
    """Sets the number of threads the parallel kernels run on (1..=MAX_THREADS); returns the
    previous count."""

# --- the kernels' vector forms (src/simd.rs)

def _set_simd(enabled: bool) -> bool:
    """Allows or forbids the kernels' vector forms (`crate::simd`); returns whether they were
    allowed. Results are the same bits either way: tests compare the two forms with it."""

def _simd_enabled() -> bool:
    """Whether the kernels run their vector forms (AVX2 detected and not switched off)."""

# --- motion (the keyframe engine)

@final
class _Keyframes:
    """Keyframes at sorted shutter times, validated and split once: rigid (K,4,4) transforms
    or deforming (K,V,3) vertex positions (src/motion/)."""

    def __new__(
        cls,
        times: np.ndarray,
        transforms: np.ndarray | None = None,
        vertices: np.ndarray | None = None,
        name: str = "transforms",
    ) -> Self:
        """times (K,) float64 strictly increasing in [0, 1] and exactly one of transforms
        (K,4,4) float64 (rotation times positive uniform scale plus translation; errors name
        ``name``: 'transforms', 'motion' or 'camera_motion') or vertices (K,V,3) float64."""
    @property
    def is_deforming(self) -> bool: ...
    def times(self) -> np.ndarray:
        """(K,) float64 keyframe times."""
    def transforms(self) -> np.ndarray:
        """(K,4,4) float64 rigid keyframes ((0,4,4) when deforming)."""
    def scales(self) -> np.ndarray:
        """(K,) float64 uniform scales of the rigid keyframes."""
    def transform_at(self, t: float) -> np.ndarray:
        """(4,4) float64 transform at shutter time t (identity when deforming)."""
    def transforms_at(self, times: np.ndarray) -> np.ndarray:
        """(N,4,4) float64 transforms at the shutter times (N,) float64."""
    def vertices_at(self, t: float) -> np.ndarray:
        """(V,3) float64 positions at shutter time t of deforming keyframes. Releases the GIL."""
    def resampled(self, segments: int) -> _Keyframes:
        """The rigid keyframes at the times i / segments (numpy.linspace), interpolated from
        the parts of these (not split again)."""

def _check_times(times: np.ndarray) -> None:
    """ValueError naming ``times`` unless (N,) float64 finite, in [0, 1], strictly increasing."""

def _rotate(angle: float, axis: np.ndarray, center: np.ndarray) -> np.ndarray:
    """(4,4) float64 rotation by angle radians about axis (3,) f64 (non-zero) through center (3,) f64."""

# --- end motion

# --- geometry (mesh, contour, motion volume, contour table)

LEADING: int
TRAILING: int
JOINING: int
MAX_SEGMENTS: int
MAX_COORD: float
FILTERS: tuple[str, ...]

@final
class _Mesh:
    """Rust mesh: owned float64 vertices (V,3), faces (F,3) and the cached edge adjacency."""

    def __new__(cls, vertices: np.ndarray, faces: np.ndarray) -> Self:
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
    keyframes: _Keyframes,
    segments: int,
    options: _VolumeOptions,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, int, float]:
    """Motion volume for rigid keyframes (K+1, at the times i/K), each interval cut into
    segments (at most MAX_SEGMENTS in total). The options (filter, colors, face_colors, normals,
    camera_position, contour_line required; visible_only, contour_table, window optional): filter
    'ramp' | 'box' | 'triangle' | 'gaussian', colors (1|V,4) float32 straight RGBA (or (F,4)
    per face with face_colors=True), normals
    (V,3) float64 | None, camera_position (3,) float64 | None, contour_line (camera: sweep only the
    contour line; False: the camera sets the alphas only), visible_only (camera and contour line:
    leave out the leading/trailing faces facing away from it), contour_table (built for this
    mesh: the split and contour of its nearest stored direction), window (a, b): the part of the
    shutter the keyframes stand for (the coverage alphas weigh it by the filter, normalised).
    Returns vertices (N,3) f64,
    faces (M,3) i64, rgba (N,4) f32, normals (N,3) f32, part (M,) u8, ring_alpha (n+1,) f64,
    the number of contour edges and the contour table's angular error (radians, 0 without).
    Releases the GIL."""

def spin_volume(
    mesh: _Mesh,
    spin: _Spin,
    options: _VolumeOptions,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, int, float]:
    """Spin volume (section 4.3): spin axis (3,) f64, angle radians, center (3,) f64,
    translation (3,) f64, segments (sweep steps) | None; the options and the result as
    motion_volume (contour_line is ignored: every contour edge is swept).
    Releases the GIL."""

@final
class _ContourTable:
    """Contour sets precomputed for K directions (section 4.4)."""

    def __new__(cls, mesh: _Mesh, count: int, seed: int, directions: np.ndarray | None = None) -> Self:
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

MAX_LENGTH: float
MAX_FPS_RATIO: float
MAX_VELOCITY: float
MAX_LEVELS: int
MAX_LAYERS: int
MAX_LENS_LEVELS: int
MAX_SAMPLES: int
MAX_TAPS: int
MIN_ALPHA: float

def _glow(alpha: np.ndarray, direction: tuple[float, float], width: float) -> np.ndarray:
    """Eq. 10 glow of alpha (H,W) f32 along direction (pixels) with half-width width (pixels).
    Returns (H,W) f32 >= alpha. Releases the GIL."""

def _box_blur(rgba: np.ndarray, direction: tuple[float, float], length: float) -> np.ndarray:
    """Box blur of rgba (H,W,4) f32 over length pixels along direction. Returns (H,W,4) f32."""

def _coverage_composite(
    back: np.ndarray,
    back_depth: np.ndarray,
    window: tuple[int, int, int, int],
    blurred: np.ndarray,
    depth: np.ndarray,
    layers: bool,
) -> tuple[np.ndarray, int]:
    """The coverage glow's composite of ``opaque_image`` over window (y0, y1, x0, x1) of the static
    colour back (H,W,4) f32 and depth back_depth (H,W) f32; blurred and depth (the blurred
    (z m, 0, 0, m)) are (y1 - y0, x1 - x0, 4) f32. Returns (the window's colour, pixels kept in
    front). Releases the GIL; the same bits for any thread count."""

def _coverage_blur(
    out: np.ndarray,
    back_depth: np.ndarray,
    rgba: np.ndarray,
    pasted: tuple[tuple[int, int, int, int], np.ndarray] | None,
    depth: np.ndarray,
    object: tuple[tuple[int, int, int, int], np.ndarray],
    parts: list[tuple[tuple[int, int, int, int], tuple[float, float], float, bool]],
    layers: bool,
    back: np.ndarray | None,
) -> int:
    """The coverage glow of ``opaque_image`` for one moving object, in place on out (H,W,4) f32
    (the colour so far) over the static depth back_depth (H,W) f32: each velocity group's layer
    cut from the sharp frame rgba (H,W,4) f32 (with pasted = (window, colour there) laid over it)
    and depth (H,W) f32, object = (window (y0, y1, x0, x1), labels (h,w) i32 there: each pixel's
    group, -1 outside the object), parts = [(window, direction, length, blur)] box-blurred,
    summed and composited. back: None, or the colour so far (H,W,4) f32, which out (then holding
    nothing yet) receives outside the object's windows. Returns the pixels kept in front.
    Releases the GIL; the same bits for any thread count."""

def _object_pixels(
    ids: np.ndarray, velocity: np.ndarray, depth: np.ndarray, window: tuple[int, int, int, int], k: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[float]]:
    """The pixels of object k in window (y0, y1, x0, x1) of a frame: ids (H,W) i32, velocity
    (H,W,2) f32, depth (H,W) f32. Returns (mask (h,w) bool: ids == k there, the velocities (N,2)
    f64 and depths (N,) f32 of its pixels in row order, their mean velocity as numpy's
    ``vs.mean(axis=0)`` gives it). Releases the GIL."""

def _one_velocity_group(velocities: np.ndarray, sectors: int, ratio: float) -> bool:
    """Whether the velocities (N,2) f64 of an object's pixels certainly all have one key of
    ``opaque_image``'s split (``sectors`` directions, lengths in bins ``ratio`` apart, numpy's
    floor of atan2 and log): each at least 1e-9 from its bins' edges (or exactly along +x).
    False: not certain."""

def _splat_paths(colors: np.ndarray, paths: np.ndarray, width: int, height: int) -> np.ndarray:
    """Time average of sources moving along image paths: colors (N,4) f32 premultiplied, paths
    (N,P,2) f32 pixel coordinates (centres at +0.5), the shutter split equally among the P - 1
    segments (P = 1: still). Returns (height, width, 4) f32. Non-finite path points drop their
    segments. Releases the GIL; the same sums for any thread count."""

def _scatter_pieces(pieces: list[_Piece], points: int, width: int, height: int) -> np.ndarray:
    """The time average (height, width, 4) f32 of sharp renders splatted along their pixels'
    image paths, the paths made on the fly. ``pieces``: dicts of rgba (H,W,4) f32 premultiplied,
    depth (H,W) f32 view depth, ids (H,W) i32, ray (4,) floats, weight float >= 0, objects (M,)
    i32, maps (M,points,4,4) f64: each pixel with alpha > 0 and an id among ``objects`` is a
    source of colour rgba * weight at the camera-space point ``z (ray[0] (i + 0.5) + ray[1],
    ray[2] (j + 0.5) + ray[3], -1)`` (z its depth), whose path point s is ``(X/W, Y/W)`` of
    ``maps[obj, s] @ (point, 1)`` (dropped when W <= 1e-9); then as ``_splat_paths``. Releases
    the GIL; the same sums for any thread count."""

def _pixel_bounds(map: np.ndarray, points: np.ndarray) -> tuple[float, float, float, float] | None:
    """(x_min, y_min, x_max, y_max) pixel bounds of points (N,3) f64 under map (4,4) f64 (rows to
    homogeneous pixels ``(x w, y w, ., w)``), or None when a point has ``w <= 1e-9`` (behind the
    camera). Releases the GIL."""

def _sample_colors(img: np.ndarray, map: np.ndarray, points: np.ndarray, rgba: np.ndarray) -> np.ndarray:
    """rgba (N,4) f32 with each point's colour replaced by the straight colour of the pixel of the
    premultiplied img (H,W,4) f32 it falls in under map (4,4) f64 (position truncated, clamped
    to the image), where that pixel's alpha is >= 1e-3 and the point is in front. Points (N,3)
    f64. Returns a new (N,4) f32. Releases the GIL."""

def _colored(rgba: np.ndarray, averaged: np.ndarray, static_rgba: np.ndarray | None = None) -> np.ndarray:
    """Per pixel of (H,W,4) f32 premultiplied images: rgba's alpha A times averaged's straight
    colour where averaged's alpha is >= 1e-3 (rgba's colour elsewhere), alpha A, plus
    (1 - A) static_rgba when given. Returns a new (H,W,4) f32. Releases the GIL."""

def _opaque_blur(rgba: np.ndarray, direction: tuple[float, float], length: float) -> np.ndarray:
    """Box blur, eq. 10 glow and eq. 7 rescale of premultiplied rgba (H,W,4) f32. Returns (H,W,4) f32."""

def _opaque_motion_blur(
    rgba: np.ndarray,
    base: np.ndarray | None,
    direction: tuple[float, float],
    length: float,
    mode: str,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """_opaque_blur composited 'over' or 'under' base (H,W,4) f32 (None: rgba). Returns (H,W,4) f32:
    ``out`` itself when given ((H,W,4) f32, C-contiguous, writable, sharing no memory with rgba
    or base; every element overwritten), else a new array."""

def _pyramid_blur(rgba: np.ndarray, levels: int) -> np.ndarray:
    """4x4-box analysis, biquadratic B-spline synthesis over levels levels. (H,W,4) f32 in and out."""

def _pyramid_glow(alpha: np.ndarray, levels: int) -> np.ndarray:
    """Pyramid glow (eqs. 8-9) of alpha (H,W) f32. Returns (H,W) f32 >= alpha."""

def _pyramid_opaque_blur(rgba: np.ndarray, levels: int) -> np.ndarray:
    """Pyramid blur rescaled to the pyramid glow (eq. 7). (H,W,4) f32 in and out."""

def _depth_of_field(rgba: np.ndarray, depth: np.ndarray, params: _DofOptions) -> np.ndarray:
    """Sub-image depth of field of rgba (H,W,4) f32 with view-axis depth (H,W) f32 (inf sky);
    params: focal_depth, focal_length in scene units, yfov radians. Returns (H,W,4) f32."""

def _lens_blur(
    rgba: np.ndarray,
    depth: np.ndarray,
    aperture: float,
    focus_distance: float,
    yfov: float,
) -> np.ndarray:
    """Thin-lens depth of field of premultiplied rgba (H,W,4) f32 with view-axis depth (H,W) f32
    (inf sky); aperture (lens radius) and focus_distance in scene units, yfov radians. Returns
    (H,W,4) f32."""

def _camera_velocity(depth: np.ndarray, camera: _CameraLike, previous_camera: _CameraLike) -> np.ndarray:
    """Velocity (H,W,2) f32 pixels (current minus previous) of depth (H,W) f32 seen by the camera
    (its view/projection (4,4) f64) when it moved from the previous one."""

def _velocity_blur(rgba: np.ndarray, velocity: np.ndarray, samples: int) -> np.ndarray:
    """Centred samples-tap blur of rgba (H,W,4) f32 along velocity (H,W,2) f32 pixels."""

def _camera_motion_blur(
    rgba: np.ndarray,
    depth: np.ndarray,
    camera: _CameraLike,
    previous_camera: _CameraLike,
    samples: int,
    scale: float,
) -> np.ndarray:
    """Chapman's camera blur: _camera_velocity times scale, then _velocity_blur. (H,W,4) f32."""

def _max_speed(velocity: np.ndarray, within: tuple[int, int, int, int] | None = None) -> float:
    """The longest velocity, max sqrt(vx^2 + vy^2) in float64, of velocity (H,W,2) f32 (NaN if any is),
    or of its window ``within`` (y0, y1, x0, x1), read in place."""

def _camera_frame_blur(
    rgba: np.ndarray,
    depth: np.ndarray,
    ids: np.ndarray,
    velocity: np.ndarray,
    moving: list[bool],
    options: _CameraFrameOptions,
) -> tuple[np.ndarray, int]:
    """The camera_velocity method's blur: each pixel's velocity its moving object's (ids (H,W) i32,
    velocity (H,W,2) f32, moving[id]) or the camera's from depth (H,W) f32, times the f32
    ``options["scale"]``, clamped to MAX_VELOCITY, then the centred ``options["samples"]``-tap
    blur of rgba (H,W,4) f32, or with ``samples`` None the line integral along each pixel's
    streak where it fits (16 taps elsewhere); ``options["camera"]`` and
    ``options["previous_camera"]`` are the two cameras. Returns (the blurred rgba (H,W,4) f32,
    pixels blurred as a line integral)."""

def _reconstruct(
    rgba: np.ndarray,
    depth: np.ndarray,
    velocity: np.ndarray,
    samples: int,
    tile: int,
    soft_depth: float,
    moving: tuple[int, int, int, int] | None = None,
) -> np.ndarray:
    """McGuire/Guertin reconstruction filter: rgba (H,W,4), depth (H,W), velocity (H,W,2) f32 -> (H,W,4) f32.
    ``moving`` (y0, y1, x0, x1): the window outside which every velocity is 0 (the caller's
    promise, not checked; only its velocities are read), None for the whole image."""

# --- end image

# --- shell (blur shells, silhouette of motion)

MAX_SUBDIVISIONS: int
MAX_HYSTERESIS: int

@final
class _BlurShell:
    """Rust blur shell (see motionblur.BlurShell). faces i64 (F,3); mask bool (F,) | None; color
    f32 (1,4) | (V,4) RGBA (the alpha scales the strips') | None (white, alpha 1)."""

    def __new__(
        cls,
        faces: np.ndarray,
        n_vertices: int,
        options: _ShellOptions,
        mask: np.ndarray | None = None,
        color: np.ndarray | None = None,
    ) -> Self: ...
    def update(self, vertices: np.ndarray, normals: np.ndarray | None = None) -> None:
        """vertices, normals f64 (V,3) C-contiguous. Releases the GIL."""
    def build(
        self, vertices: np.ndarray | None = None, normals: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(vertices f64 (N,3), faces i64 (M,3), rgba f32 (N,4) straight, normals f32 (N,3),
        face i64 (N,), step i32 (N,)). Releases the GIL."""
    def reset(self) -> None: ...
    def _history(self) -> bytes:
        """The shell's history (update count, snapshots, rings, per-polygon state) as bytes."""
    def _restore(self, state: bytes) -> None:
        """Takes the history of a shell made with the same arguments (ValueError naming state otherwise)."""
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

MAX_SIDE: int
MAX_PIXELS: int
FRAGMENT_CAP: int
MAX_INTERNAL_SIDE: int
SAMPLES: tuple[int, ...]
SHADINGS: tuple[str, ...]
BLENDS: tuple[str, ...]

def _analytic(
    draws: list[_MovingDrawLike],
    options: _AnalyticOptions,
    backdrop: _LayerLike | None = None,
) -> tuple[
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    dict[str, float],
    tuple[np.ndarray, np.ndarray, np.ndarray] | None,
]:
    """Analytic motion blur: draws (motionblur.MovingDraw: positions f64 (K+1,V,3) at the
    boundaries ``times`` f64 (K+1,) from 0 to 1, faces i64 (F,3), straight rgba f32 (1|V,4),
    normals f32 (K+1,V,3) | None, object_id, cull_back, shading "flat" | "lambert") seen through
    ``view_projections`` f64 (1|K+1,4,4) into height x width pixels of samples x samples each.
    ``shutter`` a filter name or f64 (M,) weights; ``gauss`` points per visible piece (1 to 4)
    or "auto"; ``backdrop`` an opaque layer per sample (rgba f32 (HS,WS,4), depth f32 (HS,WS),
    ids i32 (HS,WS)). Returns rgba (H,W,4) f32 premultiplied (the shutter integral), depth (H,W)
    f32, ids (H,W) i32 and velocity (H,W,2) f32 of the surface in front at ``reference_time``,
    a stats dict, and with ``exposure`` N (object ids -1..N-1) the exposure channel's fraction,
    first and last (H,W,N+1) f32 (plane N for id -1), else None. ``tile_budget`` bytes per tile
    pass; ``MemoryError`` where one sample alone needs more. The GIL is released."""

def _transform_points(m: np.ndarray, points: np.ndarray, out: np.ndarray) -> None:
    """Points (V,3) (w = 1) or (V,4) f64 under the matrix m (4,4) f64 (row-major), written into
    out (V,4) f64 (C-contiguous, writable), each component summed as (x m0 + z m2) + (y m1 + w m3)
    (the analytic method's straddle). The GIL is released."""

def _on_sample_grid(
    points: np.ndarray, view: np.ndarray, projection: np.ndarray, width: int, height: int, samples: int
) -> np.ndarray:
    """World points (V,3) f64 moved, at their clip depth, onto the rasterizer's fixed-point grid
    (1/256 of a sample) of the camera (view, projection (4,4) f64, width x height pixels) at
    samples (1, 2 or 4) a pixel side. (V,3) f64."""

def _rasterize(
    draws: list[_DrawLike],
    options: _RasterOptions,
    background: _LayerLike | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None, dict[str, float]]:
    """Render draws (motionblur.Draw: vertices f64 (V,3), faces i64 (F,3), straight rgba f32
    (1|V,4), normals f32 (V,3) | None, object_id, cull_back, previous_vertices f64 (V,3) | None)
    seen through the options' view and projection (4,4) f64 into an image of height x width.
    ``background``: optional opaque layer the frame starts from, one entry per sample (rgba f32
    (R,S,4) premultiplied, finite; depth f32 (R,S) view-axis distance > 0, inf where empty,
    pre-loading the z-buffer; ids i32 (R,S)): the frame's height * samples x width * samples
    samples are its window from the options' sample ``origin`` (x0, y0) (checked to fit);
    C-contiguous, read only. Returns rgba (H,W,4) f32 premultiplied, depth (H,W) f32 view-axis
    distance (inf background), ids (H,W) i32 (-1 background), velocity (H,W,2) f32 pixels (None
    when no draw has previous vertices: the motion is zero everywhere and is not written), and a
    stats dict. Releases the GIL."""

# --- scenes (accumulation kernels)

def _accumulate(
    acc: np.ndarray,
    rgba: np.ndarray,
    depth: np.ndarray,
    limit: np.ndarray | None,
    weight: float,
    origin: tuple[int, int] = ...,
) -> None:
    """In place: acc[y0:y0+h, x0:x0+w] (acc (H,W,4) f32) += weight * rgba (h,w,4) f32 where depth
    (h,w) f32 < limit[y0:y0+h, x0:x0+w] (limit (H,W) f32; everywhere when None), origin = (x0, y0).
    All C-contiguous. Releases the GIL."""

def _over(acc: np.ndarray, under: np.ndarray) -> None:
    """In place: acc (H,W,4) f32 += under (H,W,4) f32 * (1 - acc alpha). Releases the GIL."""

def _composite(a: _LayerLike, b: _LayerLike, origin: tuple[int, int] = ...) -> None:
    """In place into layer b (rgba (H,W,4) f32, depth (H,W) f32, ids (H,W) i32, writable): layer
    a (h,w) at origin (x0, y0) composited by depth, the nearer over the farther. Releases the
    GIL."""

def _resolve(layer: _LayerLike, samples: int, out: _LayerLike, origin: tuple[int, int] = ...) -> None:
    """In place into layer out (rgba (H,W,4) f32, depth (H,W) f32, ids (H,W) i32, writable) at
    pixel origin (x0, y0): the supersampled layer (h*s,w*s) resolved to (h,w) pixels, the mean
    colour and the nearest sample's depth and id (the first in row order on ties). Releases the
    GIL."""

# --- end scenes

# --- acc-frame (accumulation's per-frame kernels)

def _halves(
    parts: list[
        tuple[int, float, np.ndarray, tuple[int, int, int, int] | None, np.ndarray | None, int | None, float]
    ],
    window: tuple[int, int, int, int],
    pre: tuple[float, float, float, float],
) -> tuple[tuple[float, float | None, float | None], np.ndarray, tuple[float, float]]:
    """The two halves of an accumulation over ``window`` (x0, y0, x1, y1) of its (H,W) image.
    ``parts``: each (half 0 or 1, its mass (shutter weight), base (H,W,4) f32 premultiplied, its
    own window (x0, y0, x1, y1) or None, that window's drawn pixels (h,w,4) f32 or None, its
    sub-half 0 or 1 within its half or None, its end coefficient: -m for a stratified grid's
    first sample, +m for its last, m its share of the mass, else 0), all C-contiguous. Per pixel,
    in float64: each half's mass-weighted mean ``a``, ``b`` of its parts (the drawn pixels inside
    a part's window, its base outside) and ``e``, the parts' values times their end
    coefficients; returns ((the sum of the squares of ``a - b + e`` composited over the
    premultiplied RGBA ``pre``, summed along each row and then over the rows; the same of each
    half's two sub-halves plus ``2 e``, summed over both halves, when every part has a sub-half,
    else None; the same of ``a - b`` without ``e`` when a part's end coefficient is not 0, else
    None),
    the frame ``(a M_a + b M_b) / (M_a + M_b)`` (h,w,4) f32, (M_a, M_b)). ValueError naming
    ``parts``, ``base``, ``window``, ``drawn``, ``sub`` or ``end``. Releases the GIL."""

def _facing_faces(vertices: np.ndarray, faces: np.ndarray, eyes: np.ndarray) -> np.ndarray:
    """The faces (F',3) int64, in order, of the mesh vertices (V,3) float64 / faces (F,3) int64
    (object space) that face one of the object-space eye positions eyes (K,3) float64, K >= 1:
    ``n . (e_k - a) > -1e-9 |n| |e_k - a|`` for some k (n = (b - a) x (c - a)). All C-contiguous.
    ValueError for wrong shapes, non-finite values or indices outside [0, V). Releases the GIL."""

@final
class _Painter:
    """Objects drawn at any shutter time with the least per-sample work (src/accumulate/
    painter.rs): one rasterizer call per shading group, a group of one rigid object drawn in
    object space; and a whole accumulation frame's samples in one call (frame.rs)."""

    def __new__(
        cls,
        objects: list[_PaintObject],
        lights: list[_Light],
        ambient: tuple[float, float, float],
    ) -> Self:
        """objects: dicts of id, shading 'flat' | 'lambert', vertices (V,3) f64 object space,
        faces (F,3) i64, straight rgba (1|V,4) f32, normals (V,3) f32 | None, keyframes placing
        (rigid) or replacing (deforming) the vertices | None; lights: (direction, intensity)."""
    def layer(
        self, t: float, view: np.ndarray, projection: np.ndarray, width: int, height: int
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The objects at shutter time t through view and projection (4,4) f64: rgba
        (height,width,4) f32 premultiplied, depth (height,width) f32, ids (height,width) i32.
        Releases the GIL."""
    def accumulate_still(
        self,
        samples: _Samples,
        camera: _StillCamera,
        background: _LayerLike,
        opaque: bool,
    ) -> tuple[tuple[int, int, int, int], np.ndarray, np.ndarray, np.ndarray, int] | None:
        """The still-camera accumulation frame of the samples' times, weights (N,) f64
        (reference: the sample whose depth and ids are kept), the camera's matrices (4,4) f64 of
        width x height samples, aa, and the static layer (rgba (H,W,4) f32, depth (H,W) f32, ids (H,W) i32,
        C-contiguous) and its opacity: None when the objects are off the image, else the window
        (x0, y0, x1, y1), its rgba (h,w,4) f32 (static layer composited), depth, ids and the
        number of rasterizer passes. Releases the GIL."""
    def accumulate_still_parts(
        self,
        parts: list[_Samples],
        camera: _StillCamera,
        background: _LayerLike,
        opaque: bool,
        keep: int | None = None,
    ) -> list[tuple[tuple[int, int, int, int], np.ndarray, np.ndarray | None, np.ndarray | None, int] | None]:
        """`accumulate_still` of each of ``parts`` (its samples) with the same camera, static
        layer and opacity, in one call (one hand-off to the thread pool): the same frames, in
        order, the static layer cropped once for all. With ``keep`` a part's index, only that
        part has its reference sample's depth and ids (the others' are None). ValueError
        naming ``keep`` when it indexes no part. Releases the GIL."""
    def accumulate_moving(
        self,
        samples: _Samples,
        views: np.ndarray,
        projection: np.ndarray,
        width: int,
        height: int,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The moving-camera accumulation frame: one view (N,4,4) f64 per sample, projection
        (4,4) f64; rgba (height,width,4) f32 summed, depth and ids of the reference sample.
        Releases the GIL."""

# --- end acc-frame

# --- segments (the analytic method's segment rule)

__all__ += [
    "ANALYTIC_MAX_SEGMENTS",
    "ANALYTIC_MIN_PIECE",
    "ANALYTIC_NORMAL_TOLERANCE",
    "_segment_times",
]

ANALYTIC_MAX_SEGMENTS: int
ANALYTIC_MIN_PIECE: float
ANALYTIC_NORMAL_TOLERANCE: float

class _SegmentObject(TypedDict):
    mesh: _Mesh
    motion: _Keyframes | None
    lambert: bool

class _SegmentOptions(TypedDict):
    objects: list[_SegmentObject]
    width: int
    height: int
    znear: float
    view_projection: np.ndarray
    projection: np.ndarray
    pose: np.ndarray
    camera_motion: _Keyframes | None
    tolerance: float

def _segment_times(options: _SegmentOptions) -> np.ndarray:
    """(K+1,) f64 segment boundaries from 0 to 1 of the analytic method's rule for the objects
    (mesh, rigid or deforming keyframes or None, lambert) seen in a width x height image with
    near plane znear: the scene camera's view_projection, projection and pose (4,4) f64 (moved
    by camera_motion when given); tolerance pixels > 0. Releases the GIL."""

# --- end segments

__all__ += [
    "SWEEP_TIMES",
    "SWEEP_POINTS",
    "SWEEP_SHADE",
    "_sweep",
]

SWEEP_TIMES: int
SWEEP_POINTS: int
SWEEP_SHADE: float

class _SweepObject(TypedDict):
    mesh: _Mesh
    motion: _Keyframes | None
    rgba: np.ndarray

class _SweepOptions(TypedDict):
    objects: list[_SweepObject]
    width: int
    height: int
    projection: np.ndarray
    pose: np.ndarray
    camera_motion: _Keyframes | None
    background: np.ndarray

def _sweep(options: _SweepOptions) -> tuple[float, float]:
    """The planner's forecast: (scale, path), the screen sweep of the objects (mesh, rigid or
    deforming keyframes or None, straight rgba (K,4) f64: one colour or one a vertex) seen in a width x height image through
    the projection and pose (4,4) f64 (moved by camera_motion when given), over the straight
    background (4,) f64, and their mean screen path (pixels) weighted by each one's share of
    the sweep; (0.0, 0.0) when none is seen."""

# --- end sweep
