"""The analytic method's segment rule: where the shutter is cut so that every vertex moves
linearly in clip space within a segment (shared by ``analytic`` and ``auto``, which predicts the
analytic frame's cost from its segment count). The rule runs in the compiled core
(``src/analytic/segments.rs``); this module hands it the scene's objects and camera."""

from __future__ import annotations

import numpy as np

from .. import _core
from .._validate import as_float
from ..raster import Camera
from ..scene import Object, Scene

__all__ = ["segment_times", "MAX_SEGMENTS", "MIN_PIECE", "NORMAL_TOLERANCE"]

#: Most segments the automatic rule makes.
MAX_SEGMENTS: int = int(_core.ANALYTIC_MAX_SEGMENTS)
#: Shortest piece the rule halves: halving a piece that never comes straight (a point on a
#: path with a kink, a NaN) would end in equal boundaries.
MIN_PIECE: float = float(_core.ANALYTIC_MIN_PIECE)
#: Largest distance between a test vertex's unit normal at a piece's middle and the direction of
#: the mean of its normals at the piece's ends (about radians), for deforming lambert objects in
#: the segment rule: their normals are computed at every boundary and interpolated between, and
#: lambert shading moves by about this much wherever they bend.
NORMAL_TOLERANCE: float = float(_core.ANALYTIC_NORMAL_TOLERANCE)


def _object(obj: Object) -> dict:
    """What the core's rule reads of an object: its mesh, keyframes and shading."""
    return {
        "mesh": obj.mesh._core,
        "motion": None if obj.motion is None else obj.motion._keys,
        "lambert": obj.shading == "lambert",
    }


def segment_times(scene: Scene, objects, camera: Camera, tolerance: float = 0.01) -> np.ndarray:
    """(K+1,) float64 segment boundaries from 0 to 1 for ``objects`` seen by ``camera``'s image.

    The rule: the shutter is first cut at every keyframe time of the objects' motions and of
    the camera's; each piece is then halved while, at its middle, some test point lies more
    than ``tolerance`` pixels from where motion linear in clip space between the piece's ends
    puts it, as far as it can be seen: a point off the image or nearer than the near plane is
    measured as if it were at the image's border and at the near plane (its triangles show
    only there; the distance in clip space, which is linear over a triangle, is what moves
    them). Test points are the corners of each rigid object's bounding box (the farthest
    points from any rotation axis) and up to 256 vertices of each deforming one. A deforming
    lambert object's piece is also halved while a test vertex's unit normal at the middle lies
    more than `NORMAL_TOLERANCE` from the direction of the mean of its normals at the
    ends. At most `MAX_SEGMENTS` segments, none halved below `MIN_PIECE` of the
    shutter: the piece furthest over its tolerance is halved first, so a shutter that needs
    more than the cap ends with every piece about equally far off (not with its start refined
    and its end left whole). The scene's camera (moved by its ``camera_motion``) gives the
    view at each time, ``camera`` the image's size and near plane. The rule runs in the
    compiled core with the GIL released."""
    tol = as_float(tolerance, "tolerance")
    if not tol > 0:
        raise ValueError(f"tolerance: must be > 0 pixels, got {tol}")
    cam = scene.camera
    motion = scene.camera_motion
    options = {
        "objects": [_object(o) for o in objects],
        "width": camera.width,
        "height": camera.height,
        "znear": camera.znear,
        "view_projection": cam.view_projection,
        "projection": cam.projection,
        "pose": cam.pose,
        "camera_motion": None if motion is None else motion._keys,
        "tolerance": tol,
    }
    return _core._segment_times(options)
