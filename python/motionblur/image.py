"""Image-space blur kernels (Kraus's opaque image blur, pyramids, depth of field, Chapman's camera blur).

Images are float32 (H,W,4), linear RGB, premultiplied alpha, row 0 at the top; single-channel
images (alpha, depth) are float32 (H,W). Directions are (dx, dy) in pixels, +x right, +y down
(only the direction matters, not its length). Outside the image everything is transparent black,
so blurs fade to transparent at the border and the opaque blur's rescale (eq. 7) keeps the colour
there: the result does not depend on the size of the viewport (Kraus, section 3.3).

Alpha: the linear filters (``box_blur``, ``pyramid_blur``, ``velocity_blur``, ...) apply to any
finite values. The kernels whose arithmetic assumes premultiplied colour with alpha in [0, 1]
(``glow``, ``opaque_blur``, ``opaque_motion_blur`` and its ``base``, ``pyramid_glow``,
``pyramid_opaque_blur``: the glow's ``1 - (1 - a)(1 - b)``, the rescale of eq. 7 and the
``over``/``under`` composites) raise ValueError naming the argument when an alpha is outside
[0, 1] (colour is not checked against alpha).

The kernels are Rust, run on all cores (bit-identical for any thread count) and release the GIL.
The caller's arrays are never written: every function returns a new array.

Filter geometry (``box_blur``, ``glow``, ``opaque_blur``, ``opaque_motion_blur``): a box of
``length`` pixels takes ``2r + 1`` taps one *major-axis* pixel apart with
``r = floor(length * c / 2)``, ``c = max(|dx|, |dy|) / hypot(dx, dy)``; along an image axis these
are whole pixels and the cost is O(1) per pixel (running sums). Along any other direction the
image is sheared so the direction becomes a row (linear interpolation across it), the row is
filtered with running sums, and the result is sheared back (a second linear interpolation).
"""

from __future__ import annotations

import numpy as np

from . import _core
from ._validate import as_array, as_float, as_int

__all__ = [
    "box_blur",
    "camera_motion_blur",
    "camera_velocity",
    "depth_of_field",
    "glow",
    "lens_blur",
    "opaque_blur",
    "opaque_motion_blur",
    "pyramid_blur",
    "pyramid_glow",
    "pyramid_opaque_blur",
    "reconstruction_blur",
    "velocity_blur",
]

# The limits are the compiled core's.
#: Longest filter accepted, in pixels.
MAX_LENGTH: float = _core.MAX_LENGTH
#: Largest accepted ``fps`` / ``target_fps`` ratio of ``camera_motion_blur``.
MAX_FPS_RATIO: float = _core.MAX_FPS_RATIO
#: Longest velocity component [`velocity_blur`][motionblur.image.velocity_blur] takes, in pixels (a streak that long
#: crosses any image); [`camera_motion_blur`][motionblur.image.camera_motion_blur] and the ``camera_velocity`` method clamp to it.
MAX_VELOCITY: float = _core.MAX_VELOCITY
#: Most pyramid levels, depth-of-field sub-images and blur samples accepted.
MAX_LEVELS: int = _core.MAX_LEVELS
MAX_LAYERS: int = _core.MAX_LAYERS
#: Most pyramid levels of [`lens_blur`][motionblur.image.lens_blur] (a circle of confusion of radius 362 pixels).
MAX_LENS_LEVELS: int = _core.MAX_LENS_LEVELS
MAX_SAMPLES: int = _core.MAX_SAMPLES
#: Most gather taps per pixel of [`reconstruction_blur`][motionblur.image.reconstruction_blur].
MAX_TAPS: int = _core.MAX_TAPS


def _rgba(value, name="rgba", shape=None) -> np.ndarray:
    # Finite checks of the big images happen in Rust, fused with the first pass.
    a = as_array(value, name, np.float32, (None, None, 4) if shape is None else (*shape, 4), finite=False)
    return a


def _plane(value, name, shape=None) -> np.ndarray:
    return as_array(value, name, np.float32, (None, None) if shape is None else shape, finite=False)


def _direction(direction) -> tuple[float, float]:
    d = as_array(direction, "direction", np.float64, (2,))
    return float(d[0]), float(d[1])


def _length(value, name="length", maximum=MAX_LENGTH) -> float:
    if isinstance(value, (str, bytes)):
        raise TypeError(f"{name}: expected a number, got {type(value).__name__}")
    v = as_float(value, name)
    if not 0.0 <= v <= maximum:
        raise ValueError(f"{name}: must be in [0, {maximum:g}] pixels, got {v}")
    return v


def glow(alpha, direction, width) -> np.ndarray:
    """Triangle-max glow of Kraus's eq. 10 along ``direction``.

    ``A_glow[i] = max_{|k| <= w} (1 - |k| / w) A[i + k]`` with ``w = floor(width * c)`` major-axis
    taps (module docs). ``alpha``: (H,W) float32 opacity in [0, 1]; ``direction``: (2,) pixels;
    ``width``: half-width in pixels >= 0. Returns (H,W) float32, never below ``alpha``.
    """
    a = _plane(alpha, "alpha")
    return _core._glow(a, _direction(direction), _length(width, "width", MAX_LENGTH / 2))


def box_blur(rgba, direction, length) -> np.ndarray:
    """Box blur of ``length`` pixels along ``direction`` (module docs for the taps).

    ``rgba``: (H,W,4) float32 premultiplied; ``direction``: (2,) pixels; ``length``: pixels >= 0
    (0 or a zero direction return a copy). Returns (H,W,4) float32. Along an image axis the cost
    does not depend on the length (running sums).
    """
    return _core._box_blur(_rgba(rgba), _direction(direction), _length(length))


def opaque_blur(rgba, direction, length) -> np.ndarray:
    """Kraus's opaque image blur (section 3.2) along ``direction``: a box blur of ``length``
    pixels, the eq. 10 glow of the alpha with the same radius, and the rescale of eq. 7
    ``RGBA_blur * A_glow / A_blur`` (colour 0 where ``A_blur <= 1e-12``; alpha is always the glow,
    so no pixel loses opacity and the straight colour is kept where alpha grows: no dark halo).

    ``rgba``: (H,W,4) float32 premultiplied; ``direction``: (2,) pixels; ``length``: pixels >= 0.
    Returns (H,W,4) float32 premultiplied.
    """
    return _core._opaque_blur(_rgba(rgba), _direction(direction), _length(length))


def opaque_motion_blur(rgba, direction, length, mode="over", base=None, out=None) -> np.ndarray:
    """Image-based opaque motion blur (Kraus section 4.1, figures 6 and 7).

    ``rgba`` (H,W,4) float32 premultiplied is the layer that moves (the masked object for
    ``mode="over"``, the masked background for ``mode="under"``); it gets ``opaque_blur`` along
    ``direction`` (2,) over ``length`` pixels and is composited with ``base`` (H,W,4) float32
    premultiplied (default: ``rgba`` itself): ``"over"`` gives ``sub + (1 - A_sub) base`` (a
    moving foreground over the sharp image), ``"under"`` gives ``base + (1 - A_base) sub`` (a
    moving background under the sharp foreground). Returns (H,W,4) float32 premultiplied: a new
    array, or ``out`` when given (an (H,W,4) float32 C-contiguous writable array sharing no
    memory with ``rgba`` or ``base``, every element overwritten; reusing one across frames saves
    the new image's allocation). If the inputs are refused after the blur started (an image
    not premultiplied), ``out``'s contents are unspecified.
    """
    if not isinstance(mode, str):
        raise TypeError(f"mode: expected a string, got {type(mode).__name__}")
    if mode not in ("over", "under"):
        raise ValueError(f"mode: expected 'over' or 'under', got {mode!r}")
    a = _rgba(rgba)
    b = None if base is None else _rgba(base, "base", a.shape[:2])
    if out is not None:
        _check_out(out, a, b)
    return _core._opaque_motion_blur(a, b, _direction(direction), _length(length), mode, out)


def _check_out(out, *inputs) -> None:
    """``out`` is a writable C-contiguous float32 array of the first input's shape that shares no
    memory with any input; else TypeError or ValueError naming ``out``."""
    if not isinstance(out, np.ndarray):
        raise TypeError(f"out: expected a numpy array, got {type(out).__name__}")
    want = inputs[0].shape
    if out.dtype != np.float32 or out.shape != want:
        raise ValueError(f"out: expected a float32 array of shape {want}, got {out.dtype} {out.shape}")
    if not (out.flags.c_contiguous and out.flags.writeable):
        raise ValueError("out: must be C-contiguous and writable")
    if any(x is not None and np.shares_memory(out, x) for x in inputs):
        raise ValueError("out: must not share memory with rgba or base")


def _levels(levels) -> int:
    return as_int(levels, "levels", minimum=0, maximum=MAX_LEVELS)


def pyramid_blur(rgba, levels) -> np.ndarray:
    """Pyramid blur (section 3.2): ``levels`` analysis steps with a 4x4 box (each halves the size,
    rounding up, so any size works), then as many biquadratic B-spline expansions.

    ``rgba``: (H,W,4) float32; ``levels``: int in [0, 16] (0 returns a copy; the kernel's per-axis
    variance is ``4**levels / 2 - 1/4`` pixels² about its centre, that of a disc of radius
    ``sqrt(2 * 4**levels - 1)`` pixels, and its best Gaussian sigma about ``1.7 * 2**(levels - 1)``). Returns (H,W,4) float32.
    """
    return _core._pyramid_blur(_rgba(rgba), _levels(levels))


def pyramid_glow(alpha, levels) -> np.ndarray:
    """Pyramid glow (eqs. 8-9): the analysis pyramid of the blur, synthesised with
    ``A_syn = A_exp + A_ana - A_exp A_ana`` at every level, so no pixel loses opacity.

    ``alpha``: (H,W) float32 in [0, 1]; ``levels``: int in [0, 16]. Returns (H,W) float32.
    """
    return _core._pyramid_glow(_plane(alpha, "alpha"), _levels(levels))


def pyramid_opaque_blur(rgba, levels) -> np.ndarray:
    """Opaque pyramid blur: ``pyramid_blur`` rescaled to ``pyramid_glow`` of the same analysis
    pyramid (eq. 7). ``rgba``: (H,W,4) float32 premultiplied; ``levels``: int in [0, 16].
    Returns (H,W,4) float32 premultiplied.
    """
    return _core._pyramid_opaque_blur(_rgba(rgba), _levels(levels))


def depth_of_field(rgba, depth, focal_depth, focal_length, f_number, yfov, layers=5) -> np.ndarray:
    """Depth of field by sub-images with the opaque pyramid blur (Kraus section 3.1, eqs. 1-6).

    ``rgba``: (H,W,4) float32 premultiplied pinhole image; ``depth``: (H,W) float32 view-axis
    distance, > 0, ``inf`` for background (NaN raises); ``focal_depth`` and ``focal_length`` in
    scene units (> 0); ``f_number`` > 0; ``yfov`` in radians in (0, pi); ``layers``: number of
    sub-images in [1, 17], indices ``-(layers // 2) .. layers - 1 - layers // 2`` (negative in front
    of the focal plane). Sub-image ``i`` has the blur radius ``sqrt(2 * 4**|i| - 1)`` pixels (the
    disc of the ``|i|``-level pyramid blur's second moment; Kraus's eq. 1, ``1.7 * 2**(|i| - 1)``,
    is 1.6x smaller and blurred every circle of confusion 1.6x too wide), the
    thin-lens depth of eqs. 2-4 (infinite where eq. 4 turns negative; sub-images starting beyond
    infinity are dropped), the matting ramps of figure 2 and ``|i|`` pyramid levels; sub-images are
    blended over each other from far to near (eq. 6). Returns (H,W,4) float32 premultiplied.
    """
    a = _rgba(rgba)
    d = _plane(depth, "depth", a.shape[:2])
    if np.isnan(d).any():
        raise ValueError("depth: contains NaN")
    if (d <= 0).any():
        raise ValueError("depth: must be > 0 (inf for background)")
    fd = as_float(focal_depth, "focal_depth")
    fl = as_float(focal_length, "focal_length")
    fn = as_float(f_number, "f_number")
    for name, v in (("focal_depth", fd), ("focal_length", fl), ("f_number", fn)):
        if v <= 0:
            raise ValueError(f"{name}: must be > 0, got {v}")
    fov = as_float(yfov, "yfov")
    if not 0.0 < fov < np.pi:
        raise ValueError(f"yfov: must be in (0, pi) radians, got {fov}")
    n = as_int(layers, "layers", minimum=1, maximum=MAX_LAYERS)
    params = {"focal_depth": fd, "focal_length": fl, "f_number": fn, "yfov": fov, "layers": n}
    return _core._depth_of_field(a, d, params)


def lens_blur(rgba, depth, aperture, focus_distance, yfov) -> np.ndarray:
    """Depth of field of a thin lens from a pinhole image and its depth (what
    ``render(..., aperture=, focus_distance=)`` applies; Mitsuba's ``thinlens`` sensor).

    ``rgba``: (H,W,4) float32 premultiplied pinhole image, alpha in [0, 1]; ``depth``: (H,W)
    float32 view-axis distance, > 0, ``inf`` for background (NaN raises); ``aperture``: the lens's
    *radius* (Mitsuba's ``aperture_radius``) and ``focus_distance``: the focal plane's distance
    along the view axis, both scene units > 0; ``yfov``: vertical field of view in radians, in
    (0, pi). A point at depth ``z`` spreads over the circle of confusion of radius
    ``H * aperture * |1 - focus_distance / z| / (2 * focus_distance * tan(yfov / 2))`` pixels.

    Sub-images by circle of confusion, each blurred with the mixture of two kernels that has the
    disc's variance (the 3x3 binomial matches a disc of radius ``sqrt(2)`` pixels, the
    ``L``-level pyramid blur one of radius ``sqrt(2 * 4**L - 1)``), extended under
    nearer sub-images by push-pull interpolation (Kraus and Strengert 2007) and blended far to
    near with ``over``; the image border does not fade, and a last push-pull fill closes what is
    left uncovered where the pinhole image is opaque (``src/image/lens.rs``). Returns (H,W,4)
    float32 premultiplied.
    """
    a = _rgba(rgba)
    d = _depth(depth, a.shape[:2])
    ap = as_float(aperture, "aperture")
    fd = as_float(focus_distance, "focus_distance")
    for name, v in (("aperture", ap), ("focus_distance", fd)):
        if not (np.isfinite(v) and v > 0):
            raise ValueError(f"{name}: must be finite and > 0 (scene units), got {v}")
    fov = as_float(yfov, "yfov")
    if not 0.0 < fov < np.pi:
        raise ValueError(f"yfov: must be in (0, pi) radians, got {fov}")
    return _core._lens_blur(a, d, ap, fd, fov)


def _camera(camera, name, shape):
    """``camera`` (a ``motionblur.Camera`` of the image's size), checked; the core reads its
    ``view`` and ``projection``."""
    from .raster import Camera

    if not isinstance(camera, Camera):
        raise TypeError(f"{name}: expected a motionblur.Camera, got {type(camera).__name__}")
    if (camera.height, camera.width) != tuple(shape):
        raise ValueError(
            f"{name}: camera is {camera.width}x{camera.height} but the image is {shape[1]}x{shape[0]}"
        )
    return camera


def _depth(depth, shape=None) -> np.ndarray:
    d = _plane(depth, "depth", shape)
    if np.isnan(d).any():
        raise ValueError("depth: contains NaN")
    if (d <= 0).any():
        raise ValueError("depth: must be > 0 (inf for background)")
    return d


def camera_velocity(depth, camera, previous_camera) -> np.ndarray:
    """Per-pixel screen velocity of a static scene seen by a moving camera (Chapman 2011).

    ``depth``: (H,W) float32 view-axis distance seen by ``camera`` (> 0, ``inf`` for the sky,
    which then moves only with the camera's rotation); ``camera``, ``previous_camera``:
    ``motionblur.Camera`` of H x W pixels (where the camera is now and where it was when the
    shutter opened). Each pixel is moved to the previous camera with the combined matrix
    ``previous.projection @ previous.view @ inv(camera.view)``. Returns (H,W,2) float32 pixels,
    current minus previous position (+x right, +y down), like ``Frame.velocity``; 0 for points
    behind the previous camera.
    """
    d = _depth(depth)
    cam = _camera(camera, "camera", d.shape)
    prev = _camera(previous_camera, "previous_camera", d.shape)
    return _core._camera_velocity(d, cam, prev)


def velocity_blur(rgba, velocity, samples=16) -> np.ndarray:
    """Centred blur along a per-pixel velocity: ``out = mean_i I(p + v (i / (N - 1) - 1/2))`` for
    ``i = 0 .. N-1``, bilinear samples clamped to the image edge.

    ``rgba``: (H,W,4) float32; ``velocity``: (H,W,2) float32 pixels (+x right, +y down, finite,
    |v| < 1e6); ``samples``: N in [1, 1024] (1 or a zero velocity keeps the pixel).
    Returns (H,W,4) float32.
    """
    a = _rgba(rgba)
    v = as_array(velocity, "velocity", np.float32, (*a.shape[:2], 2), finite=False)
    n = as_int(samples, "samples", minimum=1, maximum=MAX_SAMPLES)
    return _core._velocity_blur(a, v, n)


def reconstruction_blur(rgba, depth, velocity, samples=16, tile=None, soft_depth=0.02) -> np.ndarray:
    """The velocity-buffer motion blur of game engines (McGuire et al. 2012's reconstruction
    filter with Guertin et al. 2014's tile max, neighbour max and foreground/background gather;
    ``src/image/reconstruct/mod.rs`` has the formulas) of one sharp frame taken at mid-shutter.

    ``rgba``: (H,W,4) float32 premultiplied; ``depth``: (H,W) float32 view-axis depth (> 0,
    ``inf`` where nothing is hit); ``velocity``: (H,W,2) float32, each pixel's screen motion over
    the whole shutter in pixels (the rasterizer's velocity buffer), the blur spanning
    ``+- velocity / 2`` around the pixel; ``samples``: gather taps per pixel, even, in
    [2, 256]; ``tile``: tile size in pixels (default: half the longest velocity, at least 8, so
    no motion is shortened; a smaller tile clamps half velocities to it); ``soft_depth``: depth
    difference, relative to depth, over which a tap goes from foreground to background (> 0).
    Deterministic (a hash of each run of eight pixels of a row jitters its taps, and the run's
    moving pixels take their second direction from its first moving pixel), the same for any
    thread count.
    Returns (H,W,4) float32 premultiplied.
    """
    a = _rgba(rgba)
    d = _depth(depth, a.shape[:2])
    v = as_array(velocity, "velocity", np.float32, (*a.shape[:2], 2), finite=False)
    n = as_int(samples, "samples", minimum=2, maximum=MAX_TAPS)
    if n % 2:
        raise ValueError(f"samples: must be even (taps come in pairs), got {n}")
    if tile is None:
        vmax = float(np.sqrt((v.astype(np.float64) ** 2).sum(axis=-1)).max()) if np.isfinite(v).all() else 0.0
        tile = max(8, int(np.ceil(0.5 * vmax)))
    t = as_int(tile, "tile", minimum=1, maximum=1 << 16)
    sd = as_float(soft_depth, "soft_depth")
    if not sd > 0:
        raise ValueError(f"soft_depth: must be > 0, got {sd}")
    return _core._reconstruct(a, d, v, n, t, sd)


def camera_motion_blur(
    rgba, depth, camera, previous_camera, samples=16, target_fps=None, fps=None
) -> np.ndarray:
    """Chapman's screen-space camera motion blur: ``camera_velocity`` then ``velocity_blur``.

    ``rgba``: (H,W,4) float32 premultiplied; ``depth``: (H,W) float32 (> 0, ``inf`` sky);
    ``camera``, ``previous_camera``: ``motionblur.Camera`` of H x W pixels; ``samples``: N in
    [1, 1024]. ``target_fps`` and ``fps`` (frames per second, both or neither): the velocity is
    scaled by ``fps / target_fps`` (at most ``MAX_FPS_RATIO``) so every frame looks as if
    rendered at the target rate. Velocities are then clamped to |v| <= 1e6 pixels (points very
    close to the previous camera's plane) before the blur.
    A static camera returns the image unchanged. Returns (H,W,4) float32 premultiplied.
    """
    a = _rgba(rgba)
    d = _depth(depth, a.shape[:2])
    cam = _camera(camera, "camera", d.shape)
    prev = _camera(previous_camera, "previous_camera", d.shape)
    n = as_int(samples, "samples", minimum=1, maximum=MAX_SAMPLES)
    if (target_fps is None) != (fps is None):
        raise ValueError("target_fps: give both target_fps and fps, or neither")
    scale = 1.0
    if fps is not None:
        t, f = as_float(target_fps, "target_fps"), as_float(fps, "fps")
        if t <= 0:
            raise ValueError(f"target_fps: must be > 0, got {t}")
        if f <= 0:
            raise ValueError(f"fps: must be > 0, got {f}")
        scale = f / t
        if not scale <= MAX_FPS_RATIO:
            raise ValueError(f"fps: fps / target_fps must be <= {MAX_FPS_RATIO:g}, got {f:g} / {t:g}")
    return _core._camera_motion_blur(a, d, cam, prev, n, scale)
