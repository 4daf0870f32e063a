"""What every public call must do with any input: raise a clear error naming an argument, or
return a valid result; leave the caller's arrays as they were; give the same bits twice."""

from __future__ import annotations

import hashlib
import time
from collections.abc import Callable, Iterable

import numpy as np
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import motionblur as mb

#: Longest a call on the suite's small inputs may take, seconds (they take milliseconds; the
#: bound catches a call whose work does not follow its arguments).
TIME_BUDGET = 20.0

#: Errors a call may raise for bad input (with the argument named in the message).
CLEAR = (ValueError, TypeError, MemoryError)

#: Any scalar a user might pass where a number, a bool or a name is expected.
JUNK = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.floats(allow_nan=True, allow_infinity=True),
    st.complex_numbers(allow_nan=True, allow_infinity=True),
    st.text(max_size=4),
    st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=5),
    st.just(object()),
    st.sampled_from([np.float32(0.5), np.int64(3), np.bool_(True), np.array(2.0), np.array([1.0, 2.0])]),
)

FLOATS = st.floats(allow_nan=True, allow_infinity=True, allow_subnormal=True)
#: Mostly tame values, sometimes NaN, inf, huge or tiny ones.
VALUES = st.one_of(
    st.floats(min_value=-10, max_value=10, allow_nan=False),
    FLOATS,
    st.sampled_from([0.0, -0.0, 1.0, 1e-300, 1e300, 1e9, -1e9, 2e9, np.nan, np.inf, -np.inf]),
)
DTYPES = st.sampled_from(
    [np.float64, np.float32, np.float16, np.int64, np.int32, np.uint8, np.bool_, np.complex128, object]
)


@st.composite
def arrays(draw, shape, dtypes=DTYPES, elements=VALUES) -> np.ndarray:
    """An array of roughly ``shape`` (a tuple of ints or strategies; sometimes one axis more or
    less, sometimes empty), of any dtype, and sometimes read-only, Fortran-ordered or a strided
    (non-contiguous) view."""
    dims = [draw(d) if isinstance(d, st.SearchStrategy) else d for d in shape]
    mutation = draw(st.sampled_from(["as is"] * 6 + ["drop axis", "add axis", "empty", "wrong length"]))
    if mutation == "drop axis" and dims:
        dims = dims[:-1]
    elif mutation == "add axis":
        dims = [*dims, 2]
    elif mutation == "empty" and dims:
        dims[0] = 0
    elif mutation == "wrong length" and dims:
        dims[-1] = draw(st.integers(0, 5))
    dtype = draw(dtypes)
    if dtype is object:
        a = np.empty(dims, object)
        a.fill(draw(st.sampled_from([None, 1.0, "x"])))
    else:
        dt = np.dtype(dtype)
        if dt.kind == "f" or dt.kind == "c":
            top = float(np.finfo(dt).max)
            els = elements.filter(lambda x: dt.kind == "c" or abs(x) <= top or not np.isfinite(x))
        elif dt.kind == "b":
            els = st.booleans()
        else:
            info = np.iinfo(dt)
            els = st.integers(max(info.min, -(10**6)), min(info.max, 10**6))
        a = draw(hnp.arrays(dt, dims, elements=els))
    layout = draw(st.sampled_from(["C"] * 4 + ["F", "strided", "readonly"]))
    if layout == "F":
        a = np.asfortranarray(a)
    elif layout == "strided" and a.ndim:
        big = np.repeat(a, 2, axis=0)
        a = big[::2]
    elif layout == "readonly":
        a = a.copy()
        a.flags.writeable = False
    return a


@st.composite
def good_or_bad(draw, good: Callable[[], object], bad: st.SearchStrategy) -> object:
    """Mostly a good value (so that the other arguments get exercised), else a bad one."""
    if draw(st.integers(0, 2)) == 0:
        return draw(bad)
    return good()


def _walk(x, seen=None) -> Iterable[np.ndarray]:
    seen = set() if seen is None else seen
    if id(x) in seen:
        return
    seen.add(id(x))
    if isinstance(x, np.ndarray):
        yield x
        if x.dtype == object:
            for item in x.ravel():
                yield from _walk(item, seen)
    elif isinstance(x, (list, tuple)):
        for item in x:
            yield from _walk(item, seen)
    elif isinstance(x, dict):
        for item in x.values():
            yield from _walk(item, seen)
    elif isinstance(x, (mb.Frame, mb.MotionVolume, mb.ShellMesh, mb.MotionSilhouette)):
        for name in ("rgba", "depth", "ids", "velocity", "vertices", "faces", "normals", "part", "ring_alpha",
                     "face", "step", "facing", "face_edge", "edges", "edge_faces"):  # fmt: skip
            if hasattr(x, name):
                yield from _walk(getattr(x, name), seen)


def digest(x) -> str:
    """A hash of every array reachable from ``x`` (values, dtype, shape) and of its scalars."""
    h = hashlib.sha256()
    for a in _walk(x):
        h.update(str((a.dtype, a.shape)).encode())
        h.update(np.ascontiguousarray(a).tobytes() if a.dtype != object else repr(a.tolist()).encode())
    if isinstance(x, (int, float, str, bool)) or x is None:
        h.update(repr(x).encode())
    elif isinstance(x, tuple):
        h.update(repr([v for v in x if isinstance(v, (int, float, str, bool))]).encode())
    return h.hexdigest()


def _outcome(call: Callable[[], object]):
    t0 = time.perf_counter()
    try:
        result = call()
    except CLEAR as exc:
        out = ("error", type(exc), str(exc)), None
    else:
        out = ("ok", digest(result)), result
    elapsed = time.perf_counter() - t0
    assert elapsed < TIME_BUDGET, f"a call took {elapsed:.1f} s (budget {TIME_BUDGET} s): {out[0][:2]}"
    return out


def check(call: Callable[[], object], inputs, names: Iterable[str]):
    """Run ``call`` twice: each within ``TIME_BUDGET``, the same outcome both times (bits of the
    result, or the error's type and message), ``inputs`` (anything holding the caller's arrays)
    unchanged, and an error
    one of ``CLEAR`` whose message starts by naming one of ``names``. Returns the result, or
    None after an error."""
    before = digest(inputs), [a.flags.writeable for a in _walk(inputs)]
    first, result = _outcome(call)
    second, _ = _outcome(call)
    assert (digest(inputs), [a.flags.writeable for a in _walk(inputs)]) == before, (
        "the caller's arrays changed"
    )
    assert first == second, f"two calls differ: {first} then {second}"
    if first[0] == "error":
        head = first[2].split(":")[0]
        assert any(n in head for n in names), (
            f"{first[1].__name__} names none of {sorted(names)}: {first[2]!r}"
        )
        return None
    return result


def finite(*arrays) -> None:
    for a in arrays:
        assert np.isfinite(a).all(), "a result holds NaN or inf"
