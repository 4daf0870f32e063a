"""Image error metrics between a rendered frame and a reference.

Every function takes Frames, (H,W,4) / (H,W,3) float arrays of premultiplied linear RGBA (RGB)
or paths of image files (``.exr``, ``.png``, read with [`motionblur.read_image`][motionblur.read_image]), with the
same shape on both sides: real numbers (no complex or object arrays), finite, not empty,
else ValueError / TypeError naming ``image`` or ``reference``. RMSE and PSNR use all four
channels (colour and coverage);
FLIP (NVIDIA's perceptual difference, pip ``flip-evaluator``) compares the frames composited
over a background, in sRGB; coverage is the alpha channel summed over the image.
"""

from __future__ import annotations

import os

import numpy as np

from .._optional import require
from .._validate import as_array, as_float
from ..interop.images import read_image
from ..raster import Frame

__all__ = ["rmse", "psnr", "flip", "coverage", "coverage_error"]


def _img(x, name: str) -> np.ndarray:
    if isinstance(x, (str, os.PathLike)):  # an image file written by Frame.save_exr / save_png
        x = read_image(x)
    a = x.rgba if isinstance(x, Frame) else x
    try:
        nd = np.ndim(a)
    except ValueError as exc:  # a ragged nested list
        raise TypeError(f"{name}: cannot be read as an array ({exc})") from None
    if nd != 3:
        raise ValueError(f"{name}: expected an (H,W,4) or (H,W,3) image or a Frame, got shape {np.shape(a)}")
    a = as_array(a, name, np.float64, (None, None, None), allow_empty=True)
    if a.shape[2] not in (3, 4):
        raise ValueError(f"{name}: expected an (H,W,4) or (H,W,3) image or a Frame, got shape {a.shape}")
    if a.size == 0:
        raise ValueError(f"{name}: is empty (shape {a.shape}); a metric of no pixels is undefined")
    return a


def _pair(image, reference) -> tuple[np.ndarray, np.ndarray]:
    a, b = _img(image, "image"), _img(reference, "reference")
    if a.shape != b.shape:
        raise ValueError(f"image: shape {a.shape} differs from the reference's {b.shape}")
    return a, b


def rmse(image, reference) -> float:
    """Root mean square difference over every pixel and channel (linear units)."""
    a, b = _pair(image, reference)
    with np.errstate(over="ignore"):
        e = float(np.sqrt(np.mean((a - b) ** 2)))
    if np.isfinite(e):
        return e
    # finite inputs whose squares (or difference) overflow float64: the same mean, rescaled
    d = 0.5 * a - 0.5 * b
    m = float(np.max(np.abs(d)))
    return 2.0 * m * float(np.sqrt(np.mean((d / m) ** 2)))


def psnr(image, reference, peak: float = 1.0) -> float:
    """Peak signal-to-noise ratio in dB, ``20 log10(peak / rmse)`` (inf for identical images);
    ``peak`` a finite number > 0 (the largest value a pixel can take, 1 for these images)."""
    peak = as_float(peak, "peak")
    if not peak > 0:
        raise ValueError(f"peak: must be > 0, got {peak}")
    e = rmse(image, reference)
    return float("inf") if e == 0 else float(20.0 * np.log10(peak / e))


def _srgb(rgba: np.ndarray, bg: np.ndarray) -> np.ndarray:
    rgb = rgba[..., :3] + (1.0 - rgba[..., 3:4]) * bg if rgba.shape[2] == 4 else rgba
    c = np.clip(rgb, 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055).astype(np.float32)


def flip(image, reference, background=(0.0, 0.0, 0.0)) -> float:
    """Mean LDR-FLIP error in [0, 1] of the two images composited over ``background`` (linear RGB,
    default black; (3,) finite and >= 0) and encoded to sRGB, at the default 67 pixels per degree."""
    bg = as_array(background, "background", np.float64, (3,))
    if (bg < 0).any():
        raise ValueError(f"background: must be >= 0, got {bg.tolist()}")
    flip_evaluator = require("flip_evaluator")
    a, b = _pair(image, reference)
    _, mean, _ = flip_evaluator.evaluate(_srgb(b, bg), _srgb(a, bg), "LDR")
    return float(mean)


def coverage(image) -> float:
    """Alpha summed over the image (pixels covered; the time-averaged coverage of a blurred frame)."""
    a = _img(image, "image")
    if a.shape[2] != 4:
        raise ValueError("image: coverage needs an alpha channel")
    return float(a[..., 3].sum())


def coverage_error(image, reference) -> float:
    """Relative error of the summed alpha, ``(coverage(image) - coverage(reference)) / coverage(reference)``
    (signed; inf when the reference covers nothing and the image does)."""
    a, b = _pair(image, reference)
    ca, cb = coverage(a), coverage(b)
    if cb == 0:
        return 0.0 if ca == 0 else float("inf")
    return (ca - cb) / cb
