"""Accumulation's time grids as ``auto`` grows them, and which grid holds which.

A grid is ``(m, kind)``: `STRATIFIED`, the midpoints of ``m`` strata of the shutter's mass
(accumulation's own ``m`` samples, `_accumulate.sample_times`); `TRAPEZOID`, the ``m + 1``
boundaries of those strata (`trapezoid_nodes`); or a refined kind (`_refine.KINDS`), the
``m`` midpoints with some boundaries added. A grid *holds* another when every time of the other
is one of its own under any shutter (`holds`): ``auto`` then keeps the samples drawn and
draws only the rest (`draws`). `next_grid` picks the grid after one for an estimated need of
samples; `holding_grid` finds the grids that hold one in closed form. Pure arithmetic on
counts and kinds (`trapezoid_nodes` alone reads the shutter).
"""

from __future__ import annotations

import math

import numpy as np

from ._accumulate import shutter_quantiles
from ._refine import ERROR_RATIO, KINDS, LEAST_STRATA
from ._refine import samples as refined_samples

__all__ = [
    "STRATIFIED",
    "TRAPEZOID",
    "MAX_SAMPLES",
    "REUSE_DRAWS",
    "trapezoid_nodes",
    "samples",
    "effective",
    "holds",
    "draws",
    "holding_families",
    "holding_grid",
    "refinements",
    "next_grid",
]

#: Accumulation's grid kinds besides the refined ones (`_refine.KINDS`): the stratified grid of
#: N samples (``accumulation``'s own) and the trapezoid grid of N strata (N + 1 samples).
STRATIFIED, TRAPEZOID = "stratified", "trapezoid"
#: Most time samples auto gives accumulation.
MAX_SAMPLES = 1 << 12
#: How many more new samples than a fresh render a refinement that keeps the drawn ones may
#: draw (`next_grid`; chosen on the tuning scenes).
REUSE_DRAWS = 1.5


def trapezoid_nodes(shutter, m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(times, weights, node) of the trapezoid grid of ``m`` strata of the shutter's mass (see
    `auto._Trials._trapezoid`), times increasing: node ``k`` at ``W^-1(k / m)``, weight 1/m (1/(2m) at
    the two ends). Where the mass ``k / m`` is reached at the start of a closed gap in the middle
    of the shutter (a weights shutter with zeros inside), the time integral jumps there, and the
    node is two samples, one at each end of the gap, each half its weight (the trapezoid rule of
    each side; one end alone would count its side twice)."""
    k = np.arange(m + 1)
    u = k / m
    left = shutter_quantiles(shutter, u)
    right = left
    if isinstance(shutter, np.ndarray):  # only a weights shutter closes inside: W's last u-time
        right = 1.0 - shutter_quantiles(np.ascontiguousarray(shutter[::-1]), 1.0 - u)
    weights = np.full(m + 1, 1.0 / m)
    weights[[0, -1]] = 0.5 / m
    gap = np.zeros(m + 1, bool)
    gap[1:-1] = right[1:-1] > left[1:-1] + 1e-12
    times = np.concatenate([left, right[gap]])
    node = np.concatenate([k, k[gap]])
    w = np.where(gap, 0.5 * weights, weights)
    weights = np.concatenate([w, w[gap]])
    order = np.argsort(times, kind="stable")
    return times[order], weights[order], node[order]


def samples(grid: tuple[int, str]) -> int:
    """The samples of a grid (m strata, its kind): m stratified, m + 1 for the trapezoid's, m and
    the boundaries added for a refined one (`_refine.samples`)."""
    m, kind = grid
    if kind in KINDS:
        return refined_samples(m, kind)
    return m + (kind == TRAPEZOID)


def effective(grid: tuple[int, str]) -> float:
    """The stratified samples whose error a grid's is about (at an error falling as 1/N): its
    samples, but a refined grid's ``m / ERROR_RATIO`` (`_refine.ERROR_RATIO`)."""
    m, kind = grid
    return m / ERROR_RATIO[kind] if kind in KINDS else float(samples(grid))


def holds(new: tuple[int, str], old: tuple[int, str]) -> bool:
    """Whether grid ``new`` holds every time of grid ``old`` (each (strata, kind)): a
    stratified grid holds one of ``m / q`` strata for odd q; a trapezoid grid holds a stratified
    or refined one of ``m / (2 q)`` strata and a trapezoid one of ``m / q``, any q; a refined
    grid holds the stratified grid of its strata and the 1/2 grid the 1/4 grid (which `refine`
    can reweight only when the stratified grid was drawn by residue: auto offers them where
    `auto._Trials.refines`)."""
    (m, kind), (m0, kind0) = new, old
    if kind == STRATIFIED:
        return kind0 == STRATIFIED and m % m0 == 0 and (m // m0) % 2 == 1
    if kind == TRAPEZOID:
        return m % m0 == 0 and (m // m0 > 1) and (kind0 == TRAPEZOID or (m // m0) % 2 == 0)
    order = [STRATIFIED, *KINDS]
    return m == m0 and kind0 in order and order.index(kind0) < order.index(kind)


def draws(new: tuple[int, str], old: tuple[int, str]) -> int:
    """The samples grid ``new`` draws after grid ``old``: all of them, less those of ``old`` it
    holds (`holds`)."""
    return samples(new) - (samples(old) if holds(new, old) else 0)


def holding_families(grid: tuple[int, str]) -> list[tuple[bool, int, int, int]]:
    """The stratified and trapezoid grids that hold ``grid``'s samples and add to them
    (`holds`), as families ``(trapezoid, first, step, last)``: strata ``j * m0`` for j = first,
    first + step, ..., last, of at most `MAX_SAMPLES` samples. Odd multiples of a stratified grid
    and trapezoid grids of its (or a refined grid's) even multiples; trapezoid grids of any
    multiple of a trapezoid grid."""
    m0, kind0 = grid
    families = [(False, 3, 2, MAX_SAMPLES // m0)] if kind0 == STRATIFIED else []
    families.append((True, 2, 1 if kind0 == TRAPEZOID else 2, (MAX_SAMPLES - 1) // m0))
    return families


def holding_grid(grid: tuple[int, str], least: float = 0.0, most: float = math.inf, largest: bool = False):
    """Of the stratified and trapezoid grids that hold ``grid``'s samples (`holding_families`)
    with between ``least`` and ``most`` samples, the one with the fewest (the most,
    ``largest``); the stratified one on a tie; None when there is none. In closed form: each
    family's samples rise with j."""
    m0, found = grid[0], []
    for trap, first, step, last in holding_families(grid):
        lo = max(first, math.ceil((least - trap) / m0))
        hi = min(last, math.floor((most - trap) / m0)) if math.isfinite(most) else last
        lo += (lo - first) % step  # onto the family's steps: up from the least
        hi -= (hi - first) % step  # and down from the most
        if lo <= hi:
            found.append(((hi if largest else lo) * m0, TRAPEZOID if trap else STRATIFIED))
    if not found:
        return None
    pick = max if largest else min
    trap_last = (lambda g: -(g[1] == TRAPEZOID)) if largest else (lambda g: g[1] == TRAPEZOID)
    return pick(found, key=lambda g: (samples(g), trap_last(g)))


def refinements(grid: tuple[int, str]) -> list[tuple[int, str]]:
    """The refined grids (`_refine.KINDS`) that hold ``grid``, of at least their
    `_refine.LEAST_STRATA`: a grid drawn by residue only (`auto._Trials.refines`)."""
    m = grid[0]
    return [(m, k) for k in KINDS if m >= LEAST_STRATA[k] and m % 2 == 0 and holds((m, k), grid)]


def next_grid(grid: tuple[int, str], want: float, refines: bool = False) -> tuple[int, str]:
    """The grid (strata, kind) after ``grid`` for an estimated need of ``want`` samples
    (stratified samples' worth: `effective`): of the grids that hold the samples drawn
    (`holding_grid`, and with ``refines`` the refined grids of the same strata,
    `refinements`) and are worth at least ``want``, the one that draws the fewest new samples
    (not the trapezoid one on a tie), when it draws at most `REUSE_DRAWS` x as many as ``want``
    rounded up to even does afresh (a render saved outweighs a few more samples, and the frame
    gets them too); else that even count, afresh."""
    fresh = min(MAX_SAMPLES, 2 * math.ceil(want / 2))
    found = [g for g in refinements(grid) if effective(g) >= want] if refines else []
    best = holding_grid(grid, least=want)
    found += [best] if best is not None else []
    if found:
        best = min(found, key=lambda g: (draws(g, grid), g[1] == TRAPEZOID))
        if draws(best, grid) <= REUSE_DRAWS * fresh:
            return best
    return (fresh, STRATIFIED)
