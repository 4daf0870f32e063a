"""Argument checking shared by the public API.

The Python layer converts dtype and contiguity (always into a fresh or read-only view, never
writing the caller's array); the Rust boundary checks shapes and ranges again. Every error
names the argument. Limits and names come from the compiled core (``_core.MAX_SEGMENTS``,
``_core.SAMPLES``, ``_core.FILTERS``, ``_core.MAX_COORD``, ...), where they are defined.

The rules, one for every entry point:

- **Arrays**: numeric and real (no complex, object, string or bool-as-number surprises),
  the documented shape, not empty, finite unless stated; converted into a fresh array or a
  read-only view, never written.
- **Scalars**: a real number (not a bool, a string, a complex), finite unless stated, in the
  documented range; an integer option is an ``int`` or numpy integer, never a float.
- **Booleans**: ``True``/``False`` or a numpy bool; anything else (``"no"``, ``0``, ``None``)
  raises TypeError.
- **Coordinates**: every position, translation, point and vector in scene units lies within
  ``+-MAX_COORD`` (1e9) in every component, so face normals, dot products and projections stay
  finite and exact enough in float32 and float64; beyond it a ValueError names the argument.
- **Colours and light**: a float or an RGB triple, finite and >= 0; alpha in [0, 1].
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from . import _core

#: Largest accepted |component| of any coordinate, in scene units (the compiled core's bound).
MAX_COORD: float = float(_core.MAX_COORD)


def as_array(
    value,
    name: str,
    dtype,
    shape: Sequence[int | None],
    *,
    allow_empty: bool = False,
    finite: bool = True,
) -> np.ndarray:
    """Return ``value`` as a C-contiguous array of ``dtype`` with the given ``shape``.

    ``None`` in ``shape`` accepts any length on that axis. Raises ``TypeError`` when the value is
    not numeric (or, for integer dtypes, not integral) and ``ValueError`` for a wrong shape, an
    empty array (unless ``allow_empty``) or non-finite values (unless ``finite=False``).
    """
    try:
        arr = np.asarray(value)
    except Exception as exc:  # pragma: no cover - numpy's own message is kept
        raise TypeError(f"{name}: cannot be read as an array ({exc})") from exc
    if arr.dtype == object or not (np.issubdtype(arr.dtype, np.number) or np.issubdtype(arr.dtype, np.bool_)):
        raise TypeError(f"{name}: expected a numeric array, got dtype {arr.dtype}")
    if np.issubdtype(arr.dtype, np.complexfloating):
        # Casting would drop the imaginary part with only a ComplexWarning.
        raise TypeError(f"{name}: expected a real array, got dtype {arr.dtype}")
    want_int = np.issubdtype(np.dtype(dtype), np.integer)
    if want_int and not np.issubdtype(arr.dtype, np.integer):
        raise TypeError(f"{name}: expected an integer array, got dtype {arr.dtype}")
    if arr.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, arr.shape)):
        want = "(" + ",".join("N" if s is None else str(s) for s in shape) + ")"
        raise ValueError(f"{name}: expected shape {want}, got {arr.shape}")
    if not allow_empty and arr.size == 0:
        raise ValueError(f"{name}: is empty")
    if want_int and arr.size:
        info = np.iinfo(dtype)
        lo, hi = arr.min(), arr.max()
        if lo < info.min or hi > info.max:
            raise ValueError(f"{name}: values out of range for {np.dtype(dtype)}")
    with np.errstate(over="ignore", invalid="ignore"):
        out = np.ascontiguousarray(arr, dtype=dtype)
    if arr.ndim == 0:  # ascontiguousarray makes a 0-d array 1-d
        out = out.reshape(())
    if finite and not want_int and out.size and not np.isfinite(out).all():
        if np.isfinite(arr).all():  # finite values past float32's range
            raise ValueError(
                f"{name}: values beyond the range of {np.dtype(dtype)} (+-{np.finfo(dtype).max:g})"
            )
        raise ValueError(f"{name}: contains NaN or inf")
    return out


def as_float(value, name: str, *, finite: bool = True) -> float:
    """A Python float from a real scalar (not a bool, a string or a complex), checked to be
    finite unless ``finite=False``."""
    if isinstance(value, (bool, np.bool_, str, bytes)) or np.iscomplexobj(value):
        raise TypeError(f"{name}: expected a real number, got {type(value).__name__}")
    try:
        out = float(value)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"{name}: expected a number, got {type(value).__name__}") from exc
    if finite and not np.isfinite(out):
        raise ValueError(f"{name}: must be finite, got {out}")
    return out


def as_int(value, name: str, *, minimum: int | None = None, maximum: int | None = None) -> int:
    """A Python int from an integral scalar, checked against the bounds."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name}: expected an integer, got {type(value).__name__}")
    out = int(value)
    if minimum is not None and out < minimum:
        raise ValueError(f"{name}: must be >= {minimum}, got {out}")
    if maximum is not None and out > maximum:
        raise ValueError(f"{name}: must be <= {maximum}, got {out}")
    return out


def as_choice(value, name: str, allowed: Sequence[str], *, type_error: bool = True) -> str:
    """``value`` when it is one of the names ``allowed``; TypeError when it is not a string
    (ValueError with ``type_error=False``, as the rendering methods' options raise), ValueError
    naming the argument and the choices otherwise."""
    if not isinstance(value, str) and type_error:
        raise TypeError(f"{name}: expected a string, got {type(value).__name__}")
    if not isinstance(value, str) or value not in allowed:
        raise ValueError(f"{name}: expected one of {', '.join(allowed)}, got {value!r}")
    return value


def as_segments(value, name: str = "segments") -> int:
    """A number of segments: an int in 1..``_core.MAX_SEGMENTS``."""
    return as_int(value, name, minimum=1, maximum=_core.MAX_SEGMENTS)


def as_samples(value, name: str) -> int:
    """Samples per pixel along each axis: one of ``_core.SAMPLES`` (1, 2 or 4)."""
    out = as_int(value, name)
    if out not in _core.SAMPLES:
        raise ValueError(f"{name}: must be one of {', '.join(map(str, _core.SAMPLES))}, got {out}")
    return out


def as_bool(value, name: str) -> bool:
    """``value`` as a bool when it is ``True``/``False`` or a numpy bool; TypeError naming the
    argument otherwise (so ``"no"``, ``0`` or ``None`` are never read as a truth value)."""
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name}: expected True or False, got {value!r}")
    return bool(value)


def as_coords(value, name: str, shape: Sequence[int | None], *, allow_empty: bool = False) -> np.ndarray:
    """``as_array`` float64 of ``shape``, finite and within ``+-MAX_COORD`` in every component."""
    out = as_array(value, name, np.float64, shape, allow_empty=allow_empty)
    check_coords(out, name)
    return out


def check_coords(arr: np.ndarray, name: str) -> None:
    """ValueError naming ``name`` when a component of the float array ``arr`` is NaN, inf or
    beyond ``+-MAX_COORD``."""
    if arr.size == 0:
        return
    m = float(np.abs(arr).max())
    if not m <= MAX_COORD:
        if not np.isfinite(arr).all():
            raise ValueError(f"{name}: contains NaN or inf")
        raise ValueError(
            f"{name}: coordinates must lie within +-{MAX_COORD:g} (the coordinate range, "
            f"motionblur.MAX_COORD), got a component of magnitude {m:g}"
        )


#: The largest finite float32: values the core holds in float32 must not exceed it.
F32_MAX = float(np.finfo(np.float32).max)


def as_rgb(value, name: str) -> np.ndarray:
    """A float or an RGB triple as a (3,) float64 array, >= 0 and finite in float32, as the
    core shades with it (light intensities, ambient light). TypeError for strings, complex
    numbers and other non-numbers."""
    if isinstance(value, (str, bytes)) or value is None:
        raise TypeError(f"{name}: expected a float or an RGB triple, got {type(value).__name__}")
    if np.ndim(value) == 0:
        if np.iscomplexobj(value):
            raise TypeError(f"{name}: expected a real number, got {type(value).__name__}")
        arr = np.full(3, as_float(value, name))
    else:
        arr = as_array(value, name, np.float64, (None,))
        if arr.shape != (3,):
            raise ValueError(f"{name}: expected a float or an RGB triple, got shape {arr.shape}")
    if (arr < 0).any():
        raise ValueError(f"{name}: must be >= 0, got {arr.tolist()}")
    if (arr > F32_MAX).any():  # the core shades in float32: it would be inf there
        raise ValueError(f"{name}: must be at most {F32_MAX!r} (float32), got {arr.tolist()}")
    return arr


def as_faces(value, name: str, n_vertices: int, *, allow_empty: bool = False) -> np.ndarray:
    """(F,3) int64 vertex indices, each in ``[0, n_vertices)``: the draws' face rule (checked
    here, when the draw is made; the core checks the indices that reach it once more)."""
    f = as_array(value, name, np.int64, (None, 3), allow_empty=allow_empty)
    if f.size and (f.min() < 0 or f.max() >= n_vertices):
        raise ValueError(f"{name}: indices must be in [0, {n_vertices}), got [{f.min()}, {f.max()}]")
    return f


def as_colors(value, name: str, n_vertices: int) -> np.ndarray:
    """The one colour rule: straight linear RGB(A), one colour (3,) or (4,) or one per vertex
    (V,3) or (V,4) with V = ``n_vertices``, RGB >= 0 and alpha in [0, 1], as float32 in the shape
    given (a read-only view: never the caller's array made writable or written). TypeError for
    strings and non-numbers, ValueError naming ``name`` otherwise."""
    if isinstance(value, (str, bytes)) or value is None:
        raise TypeError(
            f"{name}: expected an RGB(A) colour or per-vertex colours, got {type(value).__name__}"
        )
    c = np.asarray(value)
    if c.ndim <= 1:
        c = as_array(c, name, np.float32, (None,))
    else:
        c = as_array(c, name, np.float32, (n_vertices, None))
    if c.shape[-1] not in (3, 4):
        raise ValueError(f"{name}: expected (3,), (4,), (V,3) or (V,4), got shape {c.shape}")
    if (c[..., :3] < 0).any() or (c.shape[-1] == 4 and ((c[..., 3] < 0) | (c[..., 3] > 1)).any()):
        raise ValueError(f"{name}: RGB must be >= 0 and alpha in [0, 1]")
    c = c.view()
    c.flags.writeable = False
    return c


def with_alpha(colors: np.ndarray) -> np.ndarray:
    """Colours from `as_colors` as (1,4) or (V,4) float32 RGBA (alpha 1 where not given),
    C-contiguous, what the core takes."""
    c = np.atleast_2d(colors)
    if c.shape[1] == 3:
        c = np.concatenate([c, np.ones((len(c), 1), np.float32)], axis=1)
    return np.ascontiguousarray(c, dtype=np.float32)


def as_rgba(value, name: str, n_vertices: int) -> np.ndarray:
    """`as_colors` then `with_alpha`: (1,4) or (V,4) float32 straight RGBA."""
    return with_alpha(as_colors(value, name, n_vertices))


def as_list(value, name: str, item_type: type, type_name: str) -> list:
    """``value`` (one ``item_type`` or an iterable of them, not a string) as a list; TypeError
    naming the argument and the item otherwise."""
    if isinstance(value, item_type):
        return [value]
    if isinstance(value, (str, bytes)) or not hasattr(value, "__iter__"):
        raise TypeError(f"{name}: expected a sequence of {type_name}, got {type(value).__name__}")
    try:
        out = list(value)
    except TypeError as exc:  # a 0-d array, an iterator that fails
        raise TypeError(
            f"{name}: expected a sequence of {type_name}, got {type(value).__name__} ({exc})"
        ) from None
    for i, item in enumerate(out):
        if not isinstance(item, item_type):
            raise TypeError(f"{name}: item {i} is a {type(item).__name__}, not a {type_name}")
    return out


def as_path(value, name: str = "path") -> Path:
    """A ``Path`` from a str or an ``os.PathLike``; TypeError naming the argument otherwise."""
    if not isinstance(value, (str, os.PathLike)):
        raise TypeError(f"{name}: expected a str or os.PathLike file name, got {type(value).__name__}")
    return Path(value)
