"""OpenEXR files of frames: linear float colour with depth, object ids and velocity as channels.

Written and read through the official OpenEXR bindings (pip ``OpenEXR``, in the ``interop``
extra; the wheel carries the library). One single-part scanline image, ZIP compression, every
channel full resolution:

==============================  =======  ==================================================
channel                         type     content
==============================  =======  ==================================================
``R``, ``G``, ``B``, ``A``      FLOAT    premultiplied linear RGBA (EXR's own convention)
``Z``                           FLOAT    view-axis depth in scene units, ``inf`` for background
``id``                          UINT     object id: the int32's two's-complement bits
                                         (background -1 is stored as 4294967295)
``velocity.X``, ``velocity.Y``  FLOAT    screen motion over the shutter in pixels, +x right,
                                         +y down
==============================  =======  ==================================================

The header carries ``motionblur.stats`` (the frame's stats as JSON, values that JSON cannot hold
written as strings). Every value round-trips bit-exactly. This module imports nothing of the
package; [`images`][motionblur.interop.images] turns what it reads into a [`Frame`][motionblur.Frame].
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .._optional import require

__all__ = ["write_exr", "read_exr", "CHANNELS"]

#: channel names, in the order of [`read_exr`][motionblur.interop.exr.read_exr]'s arrays
CHANNELS = ("R", "G", "B", "A", "Z", "id", "velocity.X", "velocity.Y")


def _plane(a: np.ndarray, dtype) -> np.ndarray:
    # The bindings read a strided view wrongly: every plane goes in as its own C-contiguous copy.
    return np.ascontiguousarray(a, dtype=dtype)


def write_exr(path, rgba: np.ndarray, depth=None, ids=None, velocity=None, stats=None, extra=None) -> Path:
    """Write ``rgba`` (H,W,4) float32 premultiplied linear RGBA and, when given, ``depth`` (H,W)
    float32, ``ids`` (H,W) int32 and ``velocity`` (H,W,2) float32 to the EXR file ``path``
    (parent folders are created). ``stats``: a dict stored in the header as JSON. ``extra``:
    more channels by name, ``{name: (H,W) float32 or uint32 array}`` (names other than the
    module's `CHANNELS`). Returns the path. Raises ValueError
    naming the argument for wrong shapes or names."""
    openexr = require("OpenEXR", "EXR files (Frame.save_exr)")
    rgba = np.asarray(rgba)
    if rgba.ndim != 3 or rgba.shape[2] != 4 or rgba.size == 0:
        raise ValueError(f"rgba: expected shape (H,W,4), got {rgba.shape}")
    h, w = rgba.shape[:2]
    channels = {c: _plane(rgba[..., i], np.float32) for i, c in enumerate("RGBA")}
    for name, value, shape in (
        ("depth", depth, (h, w)),
        ("ids", ids, (h, w)),
        ("velocity", velocity, (h, w, 2)),
    ):
        if value is not None and np.shape(value) != shape:
            raise ValueError(f"{name}: expected shape {shape} (the rgba's), got {np.shape(value)}")
    if depth is not None:
        channels["Z"] = _plane(depth, np.float32)
    if ids is not None:
        ids = np.asarray(ids)
        if not np.issubdtype(ids.dtype, np.integer):
            raise TypeError(f"ids: expected an integer array, got dtype {ids.dtype}")
        channels["id"] = _plane(ids, np.int32).view(np.uint32)
    if velocity is not None:
        channels["velocity.X"] = _plane(np.asarray(velocity)[..., 0], np.float32)
        channels["velocity.Y"] = _plane(np.asarray(velocity)[..., 1], np.float32)
    for name, value in (extra or {}).items():
        value = np.asarray(value)
        if name in CHANNELS or name in channels or np.shape(value) != (h, w):
            raise ValueError(
                f"extra: channel {name!r} must be a new name of shape {(h, w)}, got {value.shape}"
            )
        channels[name] = _plane(value, np.uint32 if value.dtype == np.uint32 else np.float32)
    header = {"compression": openexr.ZIP_COMPRESSION, "type": openexr.scanlineimage}
    if stats:
        header["motionblur.stats"] = json.dumps(stats, default=str, sort_keys=True)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    openexr.File(header, channels).write(str(path))
    return path


def read_exr(path) -> dict:
    """The channels of the EXR file ``path``: a dict with ``rgba`` (H,W,4) float32 (RGB without
    ``A`` gets alpha 1; a lone ``Y`` is grey), and where the file has them ``depth`` (H,W)
    float32, ``ids`` (H,W) int32, ``velocity`` (H,W,2) float32, ``stats`` (dict) and ``extra``
    (``{name: (H,W) array}``, every other channel, as [`write_exr`][motionblur.interop.exr.write_exr]'s
    ``extra`` wrote it). Raises
    FileNotFoundError for a missing file and ValueError for a file without colour channels."""
    openexr = require("OpenEXR", "EXR files (read_image)")
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"path: no such file {str(path)!r}")
    f = openexr.File(str(path), separate_channels=True)
    ch = {k: v.pixels for k, v in f.channels().items()}
    if all(c in ch for c in "RGB"):
        rgb = [ch["R"], ch["G"], ch["B"]]
    elif "Y" in ch:
        rgb = [ch["Y"]] * 3
    else:
        raise ValueError(f"path: {str(path)!r} has no R, G, B or Y channel (channels: {sorted(ch)})")
    alpha = ch.get("A", np.ones_like(rgb[0], dtype=np.float32))
    out: dict = {"rgba": np.stack([*rgb, alpha], axis=-1).astype(np.float32, copy=False)}
    if "Z" in ch:
        out["depth"] = ch["Z"].astype(np.float32, copy=False)
    if "id" in ch:
        ids = ch["id"]
        out["ids"] = ids.view(np.int32) if ids.dtype == np.uint32 else ids.astype(np.int32)
    if "velocity.X" in ch and "velocity.Y" in ch:
        out["velocity"] = np.stack([ch["velocity.X"], ch["velocity.Y"]], axis=-1).astype(np.float32)
    known = set(CHANNELS) | {"Y"}
    extra = {k: v for k, v in ch.items() if k not in known}
    if extra:
        out["extra"] = extra
    stats = f.header().get("motionblur.stats")
    if isinstance(stats, str):
        out["stats"] = json.loads(stats)
    return out
