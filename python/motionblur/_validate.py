"""Argument checking shared by the public API.

The Python layer converts dtype and contiguity (always into a fresh or read-only view, never
writing the caller's array); the Rust boundary checks shapes and ranges again. Every error
names the argument. Limits and names come from the compiled core (``_core.MAX_SEGMENTS``,
``_core.SAMPLES``, ``_core.FILTERS``, ...), where they are defined.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from . import _core


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
    out = np.ascontiguousarray(arr, dtype=dtype)
    if finite and not want_int and out.size and not np.isfinite(out).all():
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
