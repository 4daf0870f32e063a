"""Motion volumes (Wloka and Zeleznik 1996): one semi-transparent volume per moving object.

The frame is rendered once, with the camera at the scene's reference time ``t_r`` (the shutter
close by default, as in the paper). Camera motion is folded into each object's motion (paper
section 3.1): the object at time ``t`` is placed where the camera at ``t_r`` sees what the camera
at ``t`` saw, ``W(t) = P(t_r) P(t)^-1 O(t)`` with ``P`` the camera pose and ``O`` the object's
transform, so a camera pan blurs the whole still scene and a camera that follows an object
leaves it sharp. For ``segments`` S the folded motion is sampled at the S + 1 times ``i / S``
and the volume joins the contour rings of those placements. Objects without apparent motion are
drawn sharp and opaque; the volumes are drawn over them with exact (depth-sorted per sample)
transparency.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_int
from ..geometry import motion_volume as build_volume
from ..raster import Draw
from ..render import Layer, raster_layer, register, resolve, supersampled
from ..scene import Object, Scene

__all__ = ["motion_volume", "apparent_keyframes"]

FILTERS = ("ramp", "box", "triangle", "gaussian")


def _rigid(scene: Scene) -> bool:
    return not any(o.is_moving and o.motion.is_deforming for o in scene.objects)


def apparent_keyframes(scene: Scene, obj: Object, segments: int) -> np.ndarray:
    """(S+1,4,4) float64 placements of ``obj`` at the times ``i / S`` as the camera at the
    reference time sees them: ``P(t_r) @ inv(P(t)) @ O(t)`` (paper section 3.1)."""
    times = np.linspace(0.0, 1.0, segments + 1)
    if not scene.camera_moves:
        return np.stack([obj.transform_at(t) for t in times])
    ref = scene.camera_pose_at(scene.reference_t)
    return np.stack([ref @ np.linalg.inv(scene.camera_pose_at(t)) @ obj.transform_at(t) for t in times])


@register(
    "motion_volume",
    sweep=[{"segments": s, "filter": f} for f in FILTERS for s in (1, 2, 4, 8)],
    applies=_rigid,
)
def motion_volume(
    scene: Scene, segments: int = 1, filter: str | None = None, aa: int = 1, contour_line: bool = True
):
    """Motion-volume rendering: each moving object becomes its motion volume, drawn transparent.

    Options: ``segments`` S >= 1 joining segments (the folded motion sampled at S + 1 times);
    ``filter`` ``"ramp"`` (the paper's), ``"box"``, ``"triangle"`` or ``"gaussian"`` (default:
    the scene's shutter filter when it is a name, else ``"box"``); ``aa`` 1, 2 or 4 spatial
    samples per pixel along each axis; ``contour_line`` (default True) sweeps only the
    camera-visible contour edges (section 4.1; the same image with back faces culled, fewer
    triangles) instead of all of them. Deforming objects raise ValueError (use
    accumulation or blur shells). Returns a Frame; ``stats`` counts the volume triangles.
    """
    segments = as_int(segments, "segments", minimum=1, maximum=4096)
    if filter is None:
        filter = scene.shutter if isinstance(scene.shutter, str) else "box"
    if not isinstance(filter, str) or filter not in FILTERS:
        raise ValueError(f"filter: expected one of {', '.join(FILTERS)}, got {filter!r}")
    aa = as_int(aa, "aa")
    if aa not in (1, 2, 4):
        raise ValueError(f"aa: must be 1, 2 or 4, got {aa}")
    tr = scene.reference_t
    cam = supersampled(scene.camera_at(tr), aa)
    eye = cam.pose[:3, 3] if contour_line else None
    draws: list[tuple[Object, Draw]] = []
    stats = {"volumes": 0, "volume_triangles": 0, "segments": segments, "filter": filter}
    for k, obj in enumerate(scene.objects):
        if obj.is_moving and obj.motion.is_deforming:
            raise ValueError(
                f"scene: object {k} ({obj.name or 'unnamed'}) deforms; motion_volume needs rigid motion "
                "(use accumulation or blur_shell)"
            )
        keys = apparent_keyframes(scene, obj, segments)
        if _still(keys):
            deforming = obj.motion is not None and obj.motion.is_deforming
            v = obj.world_vertices(tr) if deforming else _place(obj, keys[-1])
            draws.append((obj, Draw(v, obj.mesh.faces, obj.rgba, object_id=k)))
            continue
        vol = build_volume(obj.mesh, keys, segments=1, filter=filter, colors=obj.rgba, camera_position=eye)
        draws.append(
            (obj, Draw(vol.vertices, vol.faces, vol.rgba, normals=vol.normals, object_id=k, cull_back=True))
        )
        stats["volumes"] += 1
        stats["volume_triangles"] += len(vol.faces)
    layer = raster_layer(cam, scene, draws) if draws else Layer.empty(cam.height, cam.width)
    frame = resolve(layer, aa)
    frame.stats.update(stats)
    return frame


def _still(keys: np.ndarray) -> bool:
    """No apparent motion: every keyframe equals the last one up to rounding (a camera that
    follows its object folds to products like ``T P inv(T P)``, equal only to ~1e-15)."""
    scale = 1.0 + np.abs(keys[:, :3, 3]).max()
    return bool(np.abs(keys - keys[-1]).max() <= 1e-12 * scale)


def _place(obj: Object, m: np.ndarray) -> np.ndarray:
    return obj.mesh.vertices @ m[:3, :3].T + m[:3, 3]
