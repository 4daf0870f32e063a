"""`motionblur.methods._grids`: accumulation's time grids as auto grows them, checked against
their definitions (which grid holds which, by a search of every grid; the trapezoid rule's
exactness) and the planner's choices between them."""

from __future__ import annotations

import numpy as np
import pytest

from motionblur.methods import _grids as grids


def test_a_need_goes_to_the_grid_that_draws_the_fewest_new_samples():
    """From 6 samples a need of 14 goes to 18 (an odd multiple: the 6 are on its grid), drawing
    12 more, not 14 afresh plus the 6 thrown away. Where the trapezoid grid draws fewer (12 ->
    49 for 40: 37 new, not 48 for 60), it is taken, and it refines to any multiple."""
    assert grids.next_grid((6, "stratified"), 14.0) == (18, "stratified")
    assert grids.next_grid((12, "stratified"), 26.0) == (
        36,
        "stratified",
    )  # 24 new; the trapezoid's 49, 37
    assert grids.next_grid((12, "stratified"), 40.0) == (48, "trapezoid")
    assert grids.next_grid((12, "stratified"), 13.0) == (24, "trapezoid")  # 13 new, not 24
    assert grids.next_grid((24, "trapezoid"), 30.0) == (48, "trapezoid")
    assert grids.next_grid((24, "trapezoid"), 80.0) == (96, "trapezoid")
    assert grids.holds((48, "trapezoid"), (12, "stratified")) and grids.holds(
        (72, "trapezoid"), (24, "trapezoid")
    )
    assert not grids.holds((36, "trapezoid"), (12, "stratified")) and not grids.holds(
        (36, "stratified"), (12, "trapezoid")
    )


@pytest.mark.parametrize(
    "grid",
    [
        (1, "stratified"),
        (2, "stratified"),
        (6, "stratified"),
        (8, "stratified"),
        (12, "trapezoid"),
        (17, "trapezoid"),
        (96, "stratified"),
        (2047, "trapezoid"),
        (16, "refined 1/4"),
        (24, "refined 1/2"),
    ],
)
def test_the_holding_grid_is_the_one_a_search_of_every_grid_finds(grid):
    """`_holding_grid` picks in closed form; a search of every grid of at most `MAX_SAMPLES`
    samples by `_holds` (the definition of keeping the drawn samples) finds the same one, for
    needs and rooms around the family boundaries (the search once took 0.7 ms a step)."""
    most = grids.MAX_SAMPLES
    every = [
        (m, t)
        for m in range(1, most + 1)
        for t in ("stratified", "trapezoid")
        if grids.samples((m, t)) <= most
    ]
    holding = [g for g in every if grids.holds(g, grid) and grids.samples(g) > grids.samples(grid)]
    for bound in [0, 1, 2.5, 3, 9.4, 13, 17, 24.5, 25, 97, 1000, 4095, 4096, 5000]:
        enough = [g for g in holding if grids.samples(g) >= bound]
        fits = [g for g in holding if grids.samples(g) <= bound]
        want = min(enough, key=lambda g: (grids.samples(g), g[1] == "trapezoid"), default=None)
        room = max(fits, key=lambda g: (grids.samples(g), g[1] != "trapezoid"), default=None)
        assert grids.holding_grid(grid, least=bound) == want, bound
        assert grids.holding_grid(grid, most=bound, largest=True) == room, bound


def test_the_planner_refines_a_near_miss_by_boundaries_and_doubles_a_far_one():
    """From 16 stratified samples (stratified samples' worth: 1/4 is 16 / 0.907 = 17.6, 1/2 is
    20.1): a need of 17 takes the 1/4 grid (4 new samples), 19 the 1/2 grid (8), 21 the
    trapezoid grid of 32 strata (17 new; a fresh 22 would draw 22). Without refinement (aa 2
    and 4, a weights shutter) 17 goes to the trapezoid grid. Under 10 strata (12 for 1/2) the
    refined grids are not offered (at 8 the 1/2 grid's estimate spreads too much and the 1/4
    grid is worth less than auto's least next step), nor at an odd count (its last midpoint
    would weigh unlike its residue class: `refine` refuses it)."""
    g = (16, "stratified")
    assert grids.next_grid(g, 17.0, refines=True) == (16, "refined 1/4")
    assert grids.next_grid(g, 19.0, refines=True) == (16, "refined 1/2")
    assert grids.next_grid((16, "refined 1/4"), 19.0, refines=True) == (16, "refined 1/2")
    assert grids.next_grid(g, 21.0, refines=True) == (32, "trapezoid")
    assert grids.next_grid(g, 17.0, refines=False) == (32, "trapezoid")
    assert grids.next_grid((8, "stratified"), 9.5, refines=True) == (16, "trapezoid")
    assert grids.refinements((8, "stratified")) == []
    assert grids.refinements((10, "stratified")) == [(10, "refined 1/4")]
    assert grids.refinements((12, "stratified")) == [(12, "refined 1/4"), (12, "refined 1/2")]
    assert grids.refinements((13, "stratified")) == []
    assert not grids.holds((16, "refined 1/4"), (8, "stratified"))
    assert grids.holds((32, "trapezoid"), (16, "refined 1/4"))
    assert not grids.holds((48, "stratified"), (16, "refined 1/2"))


@pytest.mark.parametrize(
    "weights", [[1.0, 0.0, 0.0, 1.0], [1.0, 2.0, 0.0, 1.0], [2.0, 0.0, 1.0, 0.0, 1.0]], ids=str
)
@pytest.mark.parametrize("m", [2, 4, 8, 12])
def test_the_trapezoid_grid_splits_a_node_at_a_closed_gap(weights, m):
    """Under a weights shutter closed in the middle, the time integral jumps where the shutter's
    mass reaches the gap: a node there is two samples, one at each end, each half its weight.
    Then the rule is the trapezoid rule of each open side: exact (to rounding) for an integrand
    linear in time within every bin whenever every bin boundary's mass is a node (m a multiple
    of the weights' common denominator), and within the rule's h^2 error otherwise. With one
    end alone (the rule before), a node counted its side twice: ``t`` integrated to 0.375
    instead of 0.5 under [1, 0, 0, 1] at m = 2."""
    shutter = np.array(weights)
    times, w, node = grids.trapezoid_nodes(shutter, m)
    assert np.all(np.diff(times) >= 0) and w.sum() == pytest.approx(1.0, abs=1e-15)
    assert set(node.tolist()) == set(range(m + 1))
    bins = np.linspace(0.0, 1.0, len(shutter) + 1)
    dens = shutter / shutter.sum() * len(shutter)  # shutter density per unit time
    closed = np.flatnonzero(shutter == 0)
    for t in times:  # no sample strictly inside a closed bin
        assert not any(bins[j] + 1e-12 < t < bins[j + 1] - 1e-12 for j in closed), t
    for f in (lambda t: t, lambda t: (t - 0.3) * 2.0 + 1.0):
        exact = sum(
            dens[j] * (bins[j + 1] - bins[j]) * f(0.5 * (bins[j] + bins[j + 1])) for j in range(len(shutter))
        )
        cum = np.concatenate([[0.0], np.cumsum(shutter) / shutter.sum()])
        on_nodes = np.allclose(np.round(cum * m), cum * m)
        got = float(np.sum(w * f(times)))
        tol = 1e-12 if on_nodes else 0.5 / m**2
        assert got == pytest.approx(exact, abs=tol), (m, got, exact)
