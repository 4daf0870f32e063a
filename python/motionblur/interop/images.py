"""Reading images back as [`Frame`][motionblur.Frame]\\ s, for the metrics and for comparisons.

[`read_image`][motionblur.interop.images.read_image] reads what `Frame.save_exr` and
`Frame.save_png` write (and any other RGB(A) EXR or PNG):

- EXR: every channel as written ([`exr`][motionblur.interop.exr]), bit-exact: premultiplied linear RGBA, depth, ids,
  velocity and the stats;
- PNG (8 or 16 bit, grey or RGB, with or without alpha): straight sRGB colour decoded to linear
  and premultiplied by the alpha, as `Frame.to_srgb8` inverted
  (so within half an 8-bit step of what was saved); depth ``inf``, ids -1, velocity 0.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._optional import require
from .._validate import as_array, as_path
from ..raster import Frame
from .exr import read_exr

__all__ = ["read_image", "srgb_to_linear"]


def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    """The sRGB transfer function inverted: ``c`` in [0, 1] (any shape) to linear float32."""
    c = as_array(c, "c", np.float64, (None,) * np.ndim(c), allow_empty=True, finite=False)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4).astype(np.float32)


def _png(path: Path) -> np.ndarray:
    image = require("PIL.Image", "PNG files (read_image)")
    with image.open(path) as im:
        if im.mode in ("I;16", "I;16B", "I"):
            a = np.asarray(im, dtype=np.float64) / 65535.0
            rgba = np.stack([a, a, a, np.ones_like(a)], axis=-1)
        else:
            rgba = np.asarray(im.convert("RGBA"), dtype=np.float64) / 255.0
    lin = srgb_to_linear(rgba[..., :3])
    alpha = rgba[..., 3:4].astype(np.float32)
    return np.concatenate([lin * alpha, alpha], axis=-1).astype(np.float32)


def read_image(path) -> Frame:
    """The image file ``path`` (``.exr`` or ``.png``) as a [`Frame`][motionblur.Frame] of
    premultiplied linear RGBA (float32 (H,W,4)); see the module docs for what each format gives.

    Raises FileNotFoundError for a missing file, ValueError naming ``path`` for another suffix.
    """
    path = as_path(path)
    suffix = path.suffix.lower()
    if suffix not in (".exr", ".png"):
        raise ValueError(f"path: expected an .exr or .png file, got {str(path)!r}")
    if not path.is_file():
        raise FileNotFoundError(f"path: no such file {str(path)!r}")
    if suffix == ".png":
        rgba = _png(path)
        parts: dict = {"rgba": rgba}
    else:
        parts = read_exr(path)
        rgba = parts["rgba"]
    h, w = rgba.shape[:2]
    frame = Frame(
        rgba,
        parts.get("depth", np.full((h, w), np.inf, np.float32)),
        parts.get("ids", np.full((h, w), -1, np.int32)),
        parts.get("velocity", np.zeros((h, w, 2), np.float32)),
        stats=parts.get("stats"),
    )
    if "extra" in parts:  # the ground-truth channels Frame.save_exr wrote, by name
        frame.outputs["channels"] = parts["extra"]
    return frame
