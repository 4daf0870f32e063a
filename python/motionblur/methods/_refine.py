"""Stratified grids refined by some of their strata's boundaries: steps finer than doubling.

``auto`` refines a stratified grid of N samples (the midpoints of N strata of the shutter's
mass, `_accumulate.sample_times`) that narrowly missed its tolerance. With equal weights the
finest grid that holds its samples is the trapezoid grid of 2N strata (every midpoint and every
boundary, 2N + 1 samples). With unequal weights there are two between: the N-sample grid with
the boundaries ``b = 4i + 1`` added (``"refined 1/4"``: about N / 4 samples more), and with
``4i + 3`` as well (``"refined 1/2"``: about N / 2 more), boundaries inside the shutter only.
Every sample weighs the shutter's mass of the times nearer to it than to any other sample (its
nearest-time cell): a boundary 1 / (2N), a midpoint 1 / N less 1 / (4N) for each added boundary
beside it. Those weights are the same for every midpoint of one residue class ``i % 4`` when N
is even (an odd N's last midpoint has no boundary N beside it; `refine` refuses it), so a
grid drawn in those four parts (`_accumulate.grid_parts` with ``residues``) is reweighted part
by part, without drawing its samples again; and the boundaries ``4i + 2`` and ``4i`` complete
the trapezoid grid of 2N strata, which holds every sample of both.

For a pixel whose value steps once at a uniformly random time, the RMS error of the 1/4 grid is
0.90x the N-sample grid's and of the 1/2 grid 0.79x; on the tuning scenes 0.907x and 0.798x at
the median (`ERROR_RATIO`). Their halves (the even cells with the ``4i + 1`` boundaries, the
odd ones with ``4i + 3``) give the estimate (`_accumulate.HALVES_FACTOR`). ``auto`` refines so
at ``aa`` 1 under the box shutter only: under the other shutters the 5th percentile of
estimate / error on the tuning scenes was 0.67 (1/4) and 0.60 (1/2), against the stratified
grid's 0.73 there (and 0.93 under the box), and a frame that lands just under the tolerance
is missed by such an estimate where the doubling's overshoot hid it.
"""

from __future__ import annotations

import numpy as np

from ..scene import Scene
from ._accumulate import HalfSums, shutter_quantiles

__all__ = ["KINDS", "ERROR_RATIO", "LEAST_STRATA", "boundaries", "samples", "refine"]

#: The refined grids, each with the boundary families it adds: (``b % 4``, the half joined).
KINDS = {"refined 1/4": ((1, 0),), "refined 1/2": ((1, 0), (3, 1))}
#: Each refined grid's error over the N-sample grid's (median on the tuning scenes, seeds 0-59
#: at 96x72 and 0-39 at 192x144, 8 to 32 strata, against `motionblur.exact`; 10th-90th
#: percentiles 0.88-0.93 and 0.77-0.84).
ERROR_RATIO = {"refined 1/4": 0.907, "refined 1/2": 0.798}
#: The fewest strata a refined grid is drawn at: the 5th percentile of estimate / error of the
#: 1/2 grid at 8 strata was 0.71 on the tuning scenes (0.85-0.94 for every other count and
#: grid), too low to certify a frame by. (The 1/4 grid of 8 strata, worth 8.8 stratified
#: samples, is never worth the least auto asks after 8, 9: it starts at 10.)
LEAST_STRATA = {"refined 1/4": 10, "refined 1/2": 12}


def boundaries(n: int, residue: int) -> np.ndarray:
    """(K,) int64: the boundaries ``b`` of ``n`` strata with ``b % 4 == residue``, 0 < b < n."""
    b = np.arange(residue, n, 4, dtype=np.int64)
    return b[b > 0]


def samples(n: int, kind: str) -> int:
    """The samples of ``n`` strata refined as ``kind`` (a key of `KINDS`)."""
    return n + sum(len(boundaries(n, r)) for r, _ in KINDS[kind])


def _nodes(n: int, kind: str) -> tuple[np.ndarray, np.ndarray]:
    """(weights, half) of the trapezoid grid's nodes ``k = 0..2n`` (``k / (2n)`` of the
    shutter's mass: midpoints at odd ``k``, boundary ``b`` at ``k = 2b``) in the grid of ``n``
    strata refined as ``kind``: each sample's nearest-time cell and the half it belongs to; a
    node the grid lacks weighs 0."""
    weights, half = np.zeros(2 * n + 1), np.zeros(2 * n + 1, np.int64)
    added = np.zeros(n + 1, bool)
    for residue, h in KINDS[kind]:
        b = boundaries(n, residue)
        added[b] = True
        weights[2 * b], half[2 * b] = 0.5 / n, h
    i = np.arange(n)
    weights[2 * i + 1] = (1.0 - 0.25 * (added[i].astype(float) + added[i + 1])) / n
    half[2 * i + 1] = i % 2
    return weights, half


def refine(sums: HalfSums, scene: Scene, n: int, kind: str) -> None:
    """``sums``, which holds the stratified grid of ``n`` strata drawn by residue (or a grid of
    them refined less), refined as ``kind``: every sample drawn reweighted part by part (a part
    whose samples would weigh unequally raises ValueError: it was not drawn by residue) and
    only the boundaries it lacks drawn, each family as one part of its half."""
    if n % 2:
        raise ValueError(f"n: a refined grid needs an even number of strata, got {n}")
    weights, half = _nodes(n, kind)  # a node the grid lacks weighs 0: no sample moves there
    times = shutter_quantiles(scene.shutter, np.arange(2 * n + 1) / (2 * n))
    have = sums.regrid(times, weights, half)
    if have is None:
        raise ValueError(f"sums: a part's samples are not one residue of {n} strata")
    sums.sampling = kind
    new = []
    for residue, h in KINDS[kind]:
        k = 2 * boundaries(n, residue)
        k = k[~have[k]]
        if len(k):
            new.append((times[k], weights[k], h))
    if new:
        sums.add_all(new)
