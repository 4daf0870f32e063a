"""pyrender cameras in: ``Camera.from_pyrender`` delegates here.

A ``pyrender.PerspectiveCamera`` has the same conventions as [`Camera`][motionblur.Camera]
(camera-to-world pose, looking down -Z, ``yfov`` in radians) and the same projection matrix;
pyrender keeps the pose on the scene node and the image size on the renderer, so both are given
here. Its ``zfar=None`` (the default: an infinite projection) is ``zfar=inf`` here, which is
also this library's default, and its ``znear`` default (0.05) is ours too. pyrender is not
imported: any object with pyrender's perspective camera attributes is read.
"""

from __future__ import annotations

import math

import numpy as np

from .._validate import as_array, as_float

__all__ = ["camera_parameters", "to_pyrender_camera"]


def camera_parameters(camera, pose, width: int, height: int) -> dict:
    """Keyword arguments of [`Camera`][motionblur.Camera] (``pose``, ``yfov``, ``width``, ``height``,
    ``znear``, ``zfar``) for a ``pyrender.PerspectiveCamera`` seen from ``pose`` (4,4)
    camera-to-world (the pose of its node, ``scene.get_pose(node)``) rendering ``width`` x
    ``height`` pixels.

    Raises TypeError naming ``camera`` for pyrender's orthographic and intrinsics cameras (not
    perspective with a vertical field of view), and ValueError when the camera's own
    ``aspectRatio`` differs from ``width / height`` (pyrender would stretch the image; this
    library's projection always has the image's aspect).
    """
    kind = type(camera).__name__
    if kind != "PerspectiveCamera" or not all(hasattr(camera, a) for a in ("yfov", "znear", "zfar")):
        raise TypeError(f"camera: expected a pyrender.PerspectiveCamera, got {kind}")
    aspect = getattr(camera, "aspectRatio", None)
    if aspect is not None:
        want = float(width) / float(height)
        if not math.isclose(float(aspect), want, rel_tol=1e-6):
            raise ValueError(
                f"camera: its aspectRatio {float(aspect):g} differs from width / height = {want:g}; "
                "give the renderer's size or set aspectRatio=None"
            )
    zfar = camera.zfar
    return dict(
        pose=as_array(pose, "pose", np.float64, (4, 4)),
        yfov=as_float(camera.yfov, "camera.yfov"),
        width=width,
        height=height,
        znear=as_float(camera.znear, "camera.znear"),
        zfar=float("inf") if zfar is None else as_float(zfar, "camera.zfar", finite=False),
    )


def to_pyrender_camera(camera):
    """A ``pyrender.PerspectiveCamera`` with the projection of ``camera`` (a
    [`Camera`][motionblur.Camera]): its ``yfov``, ``znear``, ``zfar`` (``inf`` becomes pyrender's
    ``None``: passing ``inf`` to pyrender gives a NaN projection) and ``aspectRatio = width /
    height``. The pose goes on the node: ``scene.add(cam, pose=camera.pose)``."""
    from .._optional import require

    pyrender = require("pyrender", "Camera.to_pyrender")
    zfar = None if math.isinf(camera.zfar) else float(camera.zfar)
    return pyrender.PerspectiveCamera(
        yfov=float(camera.yfov),
        znear=float(camera.znear),
        zfar=zfar,
        aspectRatio=camera.width / camera.height,
    )
