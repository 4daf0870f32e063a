"""Blur shells (Jones and Keyser): each moving object trails a shell of fading quad strips.

The paper's frame (``centred=False``) is rendered once with the camera at the scene's reference
time ``t_r`` (shutter close by default). Each moving object (rigid or deforming) feeds a
[`motionblur.BlurShell`][motionblur.BlurShell] with its positions at ``subdivisions + 1`` times over ``[0, t_r]``:
updated at all but the last, built at the last, so its strips join the mesh at ``t_r`` to where
its silhouette of motion was at shutter open. The times are the quantiles of the shutter filter
(uniform for a box shutter): pair ``j`` of a strip, at alpha ``initial_alpha * (1 - j / S)``,
sits where the mesh was at the time ``t`` with ``W(t) = 1 - j / S`` (``W`` the cumulative
shutter weight over ``[0, t_r]``), which is the fraction of the shutter a long object covers a
point its trailing silhouette crossed at ``t``. Camera motion is folded into the objects'
motion as in motion volumes: the object at ``t`` is placed where the camera at ``t_r`` sees what
the camera at ``t`` saw.

The default frame (``centred=True``) is the same construction about the shutter's median time
``t_m``: the meshes sharp at ``t_m``, one shell trailing into the past (fed from shutter open
to ``t_m``) and one into the future (fed from shutter close back to ``t_m``), each ramp from
``initial_alpha / 2`` (the shutter's weight on its side) to 0.

The sharp meshes are drawn opaque, the shells over them with culling off (as the paper) and
exact per-sample depth-sorted transparency, in the object's shading (the shell keeps the mesh's
normals from when each pair was recorded).
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np

from .. import _core
from .._validate import as_array, as_bool, as_choice, as_float, as_int, as_samples
from ..raster import Draw, rasterize
from ..render import register
from ..renderer import current_renderer
from ..scene import Object, Scene
from ..shell import BlurShell
from ._layers import Layer, composite, raster_layer, resolve, supersampled

__all__ = ["blur_shell", "shell_times", "apparent_vertices"]


# Shells are kept between renders on the renderer running ([`motionblur.Renderer`][motionblur.Renderer]; their
# mesh order and vertex-face tables are costly to build for large meshes): the last 8, keyed by
# mesh identity and options, reset before reuse (a reset shell behaves exactly like a new one).
# The mesh is held so its id stays unique. A shell has state (its updates), so a render takes it
# out for its own use and puts it back after: renders of one scene in several threads at once
# never share one.


@contextmanager
def _shell_for(
    mesh, nv: int, s: int, h: int, a: float, rgba: np.ndarray, side: str = "past"
) -> Iterator[BlurShell]:
    key = (id(mesh), nv, s, h, a, rgba.shape, rgba.tobytes(), side)
    kept = current_renderer().shells
    hit = kept.take(key)
    if hit is not None and hit[0] is mesh:
        shell = hit[1]
        shell.reset()
    else:  # none kept, or another thread's render has it now
        shell = BlurShell(mesh.faces, s, h, a, color=rgba, n_vertices=nv)
    try:
        yield shell
    finally:
        kept.put(key, (mesh, shell))


def _shell_rgba(obj: Object, color: np.ndarray | None) -> np.ndarray:
    """(1,4) or (V,4) float32: the shell colour of ``obj``, ``color`` (3,) or the object's own
    RGB, with the object's alpha: a strip's alpha is the fraction of the shutter a point is
    covered, times the object's, so a translucent object's trail is as translucent as it."""
    a = obj.rgba
    rgb = a[..., :3] if color is None else np.broadcast_to(color, a[..., :3].shape)
    return np.ascontiguousarray(np.concatenate([rgb, a[..., 3:]], axis=-1).reshape(-1, 4), np.float32)


def _applies(scene: Scene) -> bool:
    return bool(scene.moving_objects) or scene.camera_moves


def shell_times(scene: Scene, subdivisions: int) -> np.ndarray:
    """(S+1,) increasing times in [0, t_r]: the quantiles ``i / S`` of the shutter's cumulative
    weight restricted to [0, t_r] (uniform for a box shutter)."""
    tr = scene.reference_t
    grid = np.linspace(0.0, tr, 4097)
    w = np.asarray(scene.shutter_cdf(grid), dtype=np.float64)
    if not w[-1] > w[0]:
        return np.linspace(0.0, tr, subdivisions + 1)
    w = (w - w[0]) / (w[-1] - w[0])
    t = np.interp(np.linspace(0.0, 1.0, subdivisions + 1), w, grid)
    t[0], t[-1] = 0.0, tr
    return np.maximum.accumulate(t)


def apparent_vertices(scene: Scene, obj: Object, t: float, seen_at: float | None = None) -> np.ndarray:
    """(V,3) float64 world positions of ``obj`` at ``t`` as the camera at ``seen_at`` (default
    the reference time ``t_r``) sees them: ``P(seen_at) @ inv(P(t))`` applied to its world
    vertices."""
    v = obj.world_vertices(t)
    if not scene.camera_moves:
        return v
    ref = scene.reference_t if seen_at is None else seen_at
    m = scene.camera_pose_at(ref) @ np.linalg.inv(scene.camera_pose_at(t))
    return v @ m[:3, :3].T + m[:3, 3]


def centred_times(scene: Scene, subdivisions: int) -> tuple[float, np.ndarray, np.ndarray]:
    """The shutter's median ``t_m`` (``W(t_m) = 1/2``) and the (S+1,) times of the two half
    shells, each ending at ``t_m``: the past one from shutter open, the future one from shutter
    close (decreasing), at the quantiles ``1/2 (1 - i/S)`` and ``1/2 (1 + i/S)`` of the
    shutter's weight, so that pair ``j`` of either shell sits where the mesh was at the time
    the shutter's weight between it and ``t_m`` is ``j / (2 S)``."""
    grid = np.linspace(0.0, 1.0, 4097)
    w = np.asarray(scene.shutter_cdf(grid), dtype=np.float64)
    w = (w - w[0]) / (w[-1] - w[0])
    q = np.arange(subdivisions + 1) / (2 * subdivisions)
    past = np.interp(q, w, grid)
    future = np.interp(1.0 - q, w, grid)
    past[0], future[0] = 0.0, 1.0
    tm = float(np.interp(0.5, w, grid))
    past[-1] = future[-1] = tm
    return tm, past, future


@register(
    "blur_shell",
    sweep=[{"subdivisions": s} for s in (2, 4, 8, 16, 32)] + [{"subdivisions": 10, "centred": False}],
    applies=_applies,
    needs="a moving object or camera",
)
def blur_shell(
    scene: Scene,
    subdivisions: int = 10,
    hysteresis: int = 3,
    initial_alpha: float = 1.0,
    color=None,
    blend: str = "nearest",
    aa: int = 1,
    centred: bool = True,
):
    """Blur-shell rendering: every moving object trails a shell of fading strips (section 3).

    Options: ``subdivisions`` S in 1..``_core.MAX_SUBDIVISIONS`` (strips of S quads, the motion sampled at S + 1
    times); ``hysteresis`` updates a polygon keeps its strip after losing its silhouette edge;
    ``initial_alpha`` in (0, 1] the alpha at the mesh (times the object's own alpha); ``color``
    RGB (3,) for every shell (speed lines), default each object's own colour; ``blend``: ``"nearest"`` (default) draws
    the shells into a buffer of their own with depth testing, so each sample takes the nearest
    shell surface's colour and alpha, then composites that buffer over the sharp meshes by depth
    (the paper's section 3.4 proposal, which stops the front and back sheets of a shell and
    overlapping strips from compounding their alpha), or ``"exact"``: every shell triangle
    blended with exact per-sample depth-sorted transparency (the paper's basic method);
    ``aa`` 1, 2 or 4 spatial samples per pixel along each axis; ``centred`` (default True):
    the sharp meshes are drawn at the shutter's median time ``t_m`` (0.5 for a box shutter)
    with two shells of ``ceil(S / 2)`` subdivisions each, one fed the positions from shutter
    open to ``t_m`` (the paper's trail into the past) and one fed them from shutter close back to
    ``t_m`` (the same construction run backwards: a trail into the future), each starting at
    ``initial_alpha / 2``, the shutter's weight on its side. A trail's ramp is the coverage of a
    point a long object left at that time; ``centred=False`` is the paper's frame, the object
    opaque at its last place with one trail from ``initial_alpha``, which over-covers every
    motion longer than the object. Returns a Frame;
    ``stats`` has ``shells``, ``shell_triangles``, ``ms_shell`` (shell updates and builds) and
    ``t`` (the time of the sharp meshes).
    """
    s = as_int(subdivisions, "subdivisions", minimum=1, maximum=_core.MAX_SUBDIVISIONS)
    h = as_int(hysteresis, "hysteresis", minimum=0, maximum=_core.MAX_HYSTERESIS)
    a = as_float(initial_alpha, "initial_alpha")
    if not 0.0 < a <= 1.0:
        raise ValueError(f"initial_alpha: must be in (0, 1], got {a}")
    if color is not None:
        color = as_array(color, "color", np.float32, (3,))
        if (color < 0).any():
            raise ValueError("color: must be >= 0")
    as_choice(blend, "blend", ("nearest", "exact"), type_error=False)
    aa = as_samples(aa, "aa")
    centred = as_bool(centred, "centred")
    if centred:
        s_side = -(-s // 2)
        tr, past, future = centred_times(scene, s_side)
        sides = [("past", past, 0.5 * a), ("future", future, 0.5 * a)]
    else:
        tr, s_side = scene.reference_t, s
        sides = [("past", shell_times(scene, s), a)]
    cam = supersampled(scene.camera_at(tr), aa)
    draws: list[tuple[Object, Draw]] = []
    shells: list[tuple[Object, Draw]] = []
    stats = {"shells": 0, "shell_triangles": 0, "ms_shell": 0.0, "subdivisions": s, "t": tr}
    for k, obj in enumerate(scene.objects):
        moving = obj.is_moving or scene.camera_moves
        current = apparent_vertices(scene, obj, tr, tr)
        draws.append((obj, Draw(current, obj.mesh.faces, obj.rgba, object_id=k)))
        if not moving:
            continue
        rgba = _shell_rgba(obj, color)
        for side, times, alpha in sides:
            if times[0] == times[-1]:
                continue  # no time on this side of the frame
            t0 = time.perf_counter()
            with _shell_for(obj.mesh, len(current), s_side, h, alpha, rgba, side) as shell:
                for t in times[:-1]:
                    shell.update(apparent_vertices(scene, obj, float(t), tr))
                mesh = shell.build(current)
            stats["ms_shell"] += (time.perf_counter() - t0) * 1e3
            if mesh.is_empty:
                continue
            (shells if blend == "nearest" else draws).append((obj, mesh.draw(object_id=k)))
            stats["shells"] += 1
            stats["shell_triangles"] += len(mesh.faces)
    layer = raster_layer(cam, scene, draws) if draws else Layer.empty(cam.height, cam.width)
    if shells:
        layer = over_by_depth(nearest_layer(cam, scene, shells), layer)
    frame = resolve(layer, aa)
    frame.stats.update(stats)
    return frame


def nearest_layer(cam, scene: Scene, shells: list[tuple[Object, Draw]]) -> Layer:
    """The shells' own buffer: per sample the nearest shell surface (depth test, culling off),
    its shaded colour and its alpha, premultiplied. Two opaque passes of the rasterizer: colour
    (in each object's shading) and alpha (flat, alpha as grey)."""
    out = None
    for shading in sorted({o.shading for o, _ in shells}):
        group = [d for o, d in shells if o.shading == shading]
        opaque = [
            _with_rgba(d, np.concatenate([d.rgba[:, :3], np.ones((len(d.rgba), 1), np.float32)], 1))
            for d in group
        ]
        alpha = [
            _with_rgba(
                d, np.concatenate([np.repeat(d.rgba[:, 3:4], 3, axis=1), np.ones_like(d.rgba[:, :1])], 1)
            )
            for d in group
        ]
        c = rasterize(cam, opaque, shading=shading, lights=scene.lights, ambient=scene.ambient)
        a = rasterize(cam, alpha, shading="flat")
        cov = a.rgba[..., :1] * c.rgba[..., 3:4]
        rgba = np.concatenate([c.rgba[..., :3] * cov, cov], axis=-1).astype(np.float32)
        depth = np.where(cov[..., 0] > 0, c.depth, np.inf).astype(np.float32)
        layer = Layer(rgba, depth, np.where(cov[..., 0] > 0, c.ids, -1).astype(np.int32))
        out = layer if out is None else composite(out, layer)
    return out


def over_by_depth(top: Layer, base: Layer) -> Layer:
    """``top`` (one transparent surface per sample) composited with ``base`` per sample: where
    ``top`` is nearer it goes *over* ``base``, elsewhere ``base`` hides it. Writes into ``base``."""
    front = top.depth < base.depth
    t = top.rgba[front]
    base.rgba[front] = t + (1.0 - t[:, 3:4]) * base.rgba[front]
    base.depth[front] = top.depth[front]
    base.ids[front] = top.ids[front]
    return base


def _with_rgba(d: Draw, rgba: np.ndarray) -> Draw:
    return Draw(
        d.vertices,
        d.faces,
        np.ascontiguousarray(rgba, np.float32),
        normals=d.normals,
        object_id=d.object_id,
        cull_back=False,
    )
