"""Blur shells (Jones and Keyser): each moving object trails a shell of fading quad strips.

The frame is rendered once with the camera at the scene's reference time ``t_r`` (shutter close
by default). Each moving object (rigid or deforming) feeds a :class:`motionblur.BlurShell` with
its positions at ``subdivisions + 1`` times over ``[0, t_r]``: updated at all but the last, built
at the last, so its strips join the mesh at ``t_r`` to where its silhouette of motion was at
shutter open. The times are the quantiles of the shutter filter (uniform for a box shutter):
pair ``j`` of a strip, at alpha ``initial_alpha * (1 - j / S)``, sits where the mesh was at the
time ``t`` with ``W(t) = 1 - j / S`` (``W`` the cumulative shutter weight over ``[0, t_r]``),
which is the fraction of the shutter a long object covers a point its trailing silhouette
crossed at ``t``. Camera motion is folded into the objects' motion as in motion volumes: the
object at ``t`` is placed where the camera at ``t_r`` sees what the camera at ``t`` saw.

The sharp meshes at ``t_r`` are drawn opaque, the shells over them with culling off (as the
paper) and exact per-sample depth-sorted transparency, in the object's shading (the shell keeps
the mesh's normals from when each pair was recorded).
"""

from __future__ import annotations

import time
from collections import OrderedDict

import numpy as np

from .. import _core
from .._validate import as_array, as_choice, as_float, as_int, as_samples
from ..raster import Draw, rasterize
from ..render import register
from ..scene import Object, Scene
from ..shell import BlurShell
from ._layers import Layer, composite, raster_layer, resolve, supersampled

__all__ = ["blur_shell", "shell_times", "apparent_vertices"]


#: Shells kept between renders (their mesh order and vertex-face tables are costly to build
#: for large meshes): the last 8, keyed by mesh identity and options, reset before reuse (a reset
#: shell behaves exactly like a new one). The mesh is held so its id stays unique.
_SHELLS: OrderedDict = OrderedDict()


def _shell_for(mesh, nv: int, s: int, h: int, a: float, rgb: np.ndarray) -> BlurShell:
    key = (id(mesh), nv, s, h, a, rgb.shape, rgb.tobytes())
    hit = _SHELLS.get(key)
    if hit is not None and hit[0] is mesh:
        _SHELLS.move_to_end(key)
        hit[1].reset()
        return hit[1]
    shell = BlurShell(mesh.faces, s, h, a, color=rgb, n_vertices=nv)
    _SHELLS[key] = (mesh, shell)
    while len(_SHELLS) > 8:
        _SHELLS.popitem(last=False)
    return shell


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


def apparent_vertices(scene: Scene, obj: Object, t: float) -> np.ndarray:
    """(V,3) float64 world positions of ``obj`` at ``t`` as the camera at the reference time
    sees them: ``P(t_r) @ inv(P(t))`` applied to its world vertices."""
    v = obj.world_vertices(t)
    if not scene.camera_moves:
        return v
    m = scene.camera_pose_at(scene.reference_t) @ np.linalg.inv(scene.camera_pose_at(t))
    return v @ m[:3, :3].T + m[:3, 3]


@register(
    "blur_shell",
    sweep=[{"subdivisions": s} for s in (2, 4, 8, 16, 32)],
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
):
    """Blur-shell rendering: every moving object trails a shell of fading strips (section 3).

    Options: ``subdivisions`` S in 1..``_core.MAX_SUBDIVISIONS`` (strips of S quads, the motion sampled at S + 1
    times); ``hysteresis`` updates a polygon keeps its strip after losing its silhouette edge;
    ``initial_alpha`` in (0, 1] the alpha at the mesh; ``color`` RGB (3,) for every shell
    (speed lines), default each object's own colour; ``blend``: ``"nearest"`` (default) draws
    the shells into a buffer of their own with depth testing, so each sample takes the nearest
    shell surface's colour and alpha, then composites that buffer over the sharp meshes by depth
    (the paper's section 3.4 proposal, which stops the front and back sheets of a shell and
    overlapping strips from compounding their alpha), or ``"exact"``: every shell triangle
    blended with exact per-sample depth-sorted transparency (the paper's basic method);
    ``aa`` 1, 2 or 4 spatial samples per pixel along each axis. Returns a Frame; ``stats`` has ``shells``, ``shell_triangles`` and
    ``ms_shell`` (shell updates and builds).
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
    tr = scene.reference_t
    cam = supersampled(scene.camera_at(tr), aa)
    times = shell_times(scene, s)
    draws: list[tuple[Object, Draw]] = []
    shells: list[tuple[Object, Draw]] = []
    stats = {"shells": 0, "shell_triangles": 0, "ms_shell": 0.0, "subdivisions": s}
    for k, obj in enumerate(scene.objects):
        moving = obj.is_moving or scene.camera_moves
        current = apparent_vertices(scene, obj, tr)
        draws.append((obj, Draw(current, obj.mesh.faces, obj.rgba, object_id=k)))
        if not moving or tr == 0.0:
            continue
        t0 = time.perf_counter()
        rgb = np.ascontiguousarray(color if color is not None else obj.rgba[..., :3], np.float32)
        shell = _shell_for(obj.mesh, len(current), s, h, a, rgb)
        for t in times[:-1]:
            shell.update(apparent_vertices(scene, obj, float(t)))
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
