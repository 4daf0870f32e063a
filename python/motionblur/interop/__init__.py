"""Interop with the tools graphics researchers already use.

- [`trimesh`][motionblur.interop.trimesh]: ``Scene.from_trimesh`` (a ``trimesh.Scene`` with its graph transforms and
  colours) and ``Mesh.to_trimesh``;
- [`gltf`][motionblur.interop.gltf] (with `_gltf_data`): ``Scene.from_gltf``, animated glTF 2.0 (node
  hierarchy, TRS keyframes, morph targets, skins) over a shutter interval;
- [`pyrender`][motionblur.interop.pyrender]: ``Camera.from_pyrender``;
- [`mitsuba`][motionblur.interop.mitsuba]: [`to_mitsuba_dict`][motionblur.interop.to_mitsuba_dict], the Mitsuba 3 scene dictionary of a scene at a time;
- [`exr`][motionblur.interop.exr] and [`images`][motionblur.interop.images]: ``Frame.save_exr`` and [`read_image`][motionblur.interop.read_image] (EXR and PNG back
  into a Frame, for the metrics).

The classes' methods (``Scene.from_trimesh`` ...) import these modules when called; these
modules import the classes' modules, never the other way at import time, so there is no
import cycle. The third-party packages come with ``pip install "motionblur[interop]"`` (Mitsuba
with ``[reference]``) and are imported on first use.
"""

from __future__ import annotations

from .images import read_image
from .mitsuba import to_mitsuba_dict

__all__ = ["read_image", "to_mitsuba_dict"]


from .._namespace import tidy  # noqa: E402  (dir() lists the API only; see motionblur._namespace)

tidy(__name__, walk=True)
