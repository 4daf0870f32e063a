"""The memory budget: the most bytes one call may allocate (docs: guide/resources.md, "Memory and time budgets").

Every kernel whose memory is a product of sizes (pixels x samples, faces x directions,
faces x segments, vertices x subdivisions, ...) computes what it will allocate before it
allocates anything and raises ``MemoryError`` naming those arguments and the bytes when that is
over the budget; a count so large that its bytes overflow 64 bits raises ``ValueError``. An
allocation the system refuses within the budget (a process under ``ulimit -v``) is a
``MemoryError`` too, never an abort of the interpreter.

The budget is one number for the process, `DEFAULT_MEMORY_BUDGET` (4 GiB, whatever the
machine, so that a call accepted on one machine is accepted on every other) unless the
environment sets ``MOTIONBLUR_MEMORY_BUDGET`` (bytes) when the package is imported.
[`set_memory_budget`][motionblur.budget.set_memory_budget] changes it; [`memory_budget`][motionblur.budget.memory_budget] reads it.
"""

from __future__ import annotations

import os

from . import _core

__all__ = ["memory_budget", "set_memory_budget", "need", "DEFAULT_MEMORY_BUDGET", "MIN_MEMORY_BUDGET"]

#: The default budget in bytes (4 GiB).
DEFAULT_MEMORY_BUDGET: int = _core.DEFAULT_MEMORY_BUDGET
#: The smallest budget accepted (1 MiB).
MIN_MEMORY_BUDGET: int = _core.MIN_MEMORY_BUDGET

_ENV = "MOTIONBLUR_MEMORY_BUDGET"


def memory_budget() -> int:
    """The most bytes one call may allocate."""
    return int(_core.memory_budget())


def set_memory_budget(bytes: int) -> int:  # noqa: A002 - the unit is the argument's name
    """Set the memory budget to ``bytes`` (an int >= ``MIN_MEMORY_BUDGET``); returns the
    previous budget, so that ``old = set_memory_budget(n)`` ... ``set_memory_budget(old)``
    restores it."""
    if isinstance(bytes, bool) or not hasattr(bytes, "__index__"):
        raise TypeError(f"bytes: expected an integer, got {type(bytes).__name__}")
    n = int(bytes.__index__())
    if not MIN_MEMORY_BUDGET <= n < 1 << 64:
        raise ValueError(f"bytes: the memory budget must be in {MIN_MEMORY_BUDGET}..2**64-1, got {n}")
    return int(_core.set_memory_budget(n))


def _short(n: int) -> str:
    for unit, size in (("GB", 10**9), ("MB", 10**6)):
        if n >= size:
            return f"{n / size:.2f} {unit}"
    return f"{n / 1e3:.2f} kB"


def _human(n: int) -> str:
    return f"{_short(n)} ({n} bytes)"


def need(call: str, *terms: tuple[dict[str, int], int]) -> int:
    """The bytes of ``terms`` (each ``({argument: size, ...}, bytes_each)``: the product of the
    sizes times the bytes each), checked as the core checks its own: ``ValueError`` when it
    overflows 64 bits, ``MemoryError`` naming the largest term's arguments when it is over the
    budget. For the checks the Python layer makes before calling the core (a running total
    of images, an array too large to convert)."""
    parts = []
    total = 0
    for sizes, each in terms:
        b = each
        for v in sizes.values():
            b *= int(v)
        names = " x ".join(sizes)
        values = " x ".join(str(int(v)) for v in sizes.values())
        if b >= 1 << 64:
            raise ValueError(
                f"{next(iter(sizes))}: {names} = {values} is absurd: its memory overflows 64 bits"
            )
        parts.append((names, values, b))
        total += b
    budget = memory_budget()
    if total > budget:
        largest = max(parts, key=lambda p: p[2])[0]
        listed = " + ".join(f"{n} = {v} ({_short(b)})" for n, v, b in parts)
        raise MemoryError(
            f"{largest}: {call} needs {_human(total)}: {listed}; over the memory budget of "
            f"{_human(budget)} (motionblur.set_memory_budget raises it)"
        )
    return total


def _on_import() -> None:
    value = os.environ.get(_ENV, "").strip()
    if not value:
        return
    try:
        n = int(value)
    except ValueError:
        raise ValueError(f"{_ENV}: expected a number of bytes, got {value!r}") from None
    set_memory_budget(n)


_on_import()
