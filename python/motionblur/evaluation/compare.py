"""Comparisons of the report's rows, pure arithmetic on them (nothing is rendered here).

A row is a dict with at least ``method``, ``ms`` and an error column (``rmse``, ``flip``).

- `pareto_front`: the rows no other row beats in both time and error.
- `equal_error`: for each motion-volume row, the time accumulation needs for the same
  error, interpolated log-log between the two sample counts that bracket it (if even N = 1 is
  better, its time is an upper bound, marked ``<=``; if even the largest N is worse, ``>=``).
- `equal_time`: for each row of another method, accumulation's error in the same time.
- `front_row`, `front_time`, `landing`: where an ``auto`` row lands against
  the fastest swept run at least as accurate.
"""

from __future__ import annotations

import math

__all__ = ["pareto_front", "equal_error", "equal_time", "front_row", "front_time", "landing"]


def pareto_front(rows) -> list[bool]:
    """Whether each row is on the Pareto front of (ms, rmse): no other row is at least as fast
    and as accurate and strictly better in one."""
    out = []
    for r in rows:
        dominated = any(
            (o["ms"] <= r["ms"] and o["rmse"] <= r["rmse"]) and (o["ms"] < r["ms"] or o["rmse"] < r["rmse"])
            for o in rows
        )
        out.append(not dominated)
    return out


def equal_error(rows, method="motion_volume", baseline="accumulation", metric="rmse"):
    """For each ``method`` row of one scene: (row, baseline ms at the same error, bound, factor);
    bound is ``""``, ``"<="`` or ``">="`` (see the module docs). ``metric``: ``"rmse"`` or
    ``"flip"`` (any positive error column of the rows)."""
    base = sorted((r for r in rows if r["method"] == baseline), key=lambda r: r["ms"])
    if not base:
        return []
    # errors of the baseline as its cost grows, made monotone (the best error reached so far)
    pts, best = [], float("inf")
    for r in base:
        if r[metric] < best:
            best = r[metric]
            pts.append((r["ms"], r[metric]))
    out = []
    for r in rows:
        if r["method"] != method:
            continue
        e = r[metric]
        if not (e > 0 and math.isfinite(e)):
            continue
        if e >= pts[0][1]:
            t, bound = pts[0][0], "<="
        elif e < pts[-1][1]:
            t, bound = pts[-1][0], ">="
        else:
            for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
                if e1 <= e < e0 or e == e0:
                    u = (math.log(e0) - math.log(e)) / (math.log(e0) - math.log(e1)) if e0 != e1 else 0.0
                    t = math.exp(math.log(t0) + u * (math.log(t1) - math.log(t0)))
                    bound = ""
                    break
        out.append((r, t, bound, t / r["ms"]))
    return out


def _envelope(rows, baseline: str, metric: str):
    """(ms, error) of the ``baseline`` rows sorted by time, kept only where the error improves
    (the best error reached for that time or less)."""
    pts, best = [], float("inf")
    for r in sorted((r for r in rows if r["method"] == baseline), key=lambda r: r["ms"]):
        e = r[metric]
        if math.isfinite(e) and e > 0 and e < best:
            best = e
            pts.append((r["ms"], e))
    return pts


def equal_time(rows, methods=None, baseline="accumulation", metric="rmse"):
    """Each method's error beside the baseline's at the same time, for the rows of one scene.

    For every row of a method other than ``baseline`` (or of ``methods``): ``(row, baseline
    error at the row's time, bound, ratio)``. The baseline's error against time is its lower
    envelope (the best error reached in that time or less), interpolated log-log between the
    two timings that bracket the row's time. If the row is faster than the fastest baseline
    run, the baseline cannot be run in that time: its fastest error is a lower bound (``">="``);
    if slower than the slowest, the slowest's error is an upper bound (``"<="``); else ``""``.
    ``ratio`` = baseline error / the row's error (> 1: the method is more accurate than the
    baseline in the same time)."""
    pts = _envelope(rows, baseline, metric)
    if not pts:
        return []
    out = []
    for r in rows:
        if r["method"] == baseline or (methods is not None and r["method"] not in methods):
            continue
        e, t = r[metric], r["ms"]
        if not (e > 0 and math.isfinite(e) and t > 0):
            continue
        if t < pts[0][0]:
            eb, bound = pts[0][1], ">="
        elif t >= pts[-1][0]:
            eb, bound = pts[-1][1], "<=" if t > pts[-1][0] else ""
        else:
            for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
                if t0 <= t < t1:
                    u = (math.log(t) - math.log(t0)) / (math.log(t1) - math.log(t0))
                    eb, bound = math.exp(math.log(e0) + u * (math.log(e1) - math.log(e0))), ""
                    break
        out.append((r, eb, bound, eb / e))
    return out


#: Rows of these methods are left out of the fronts (the planner is measured against them).
_SKIP = ("auto",)


def front_row(rows, error: float, metric: str = "rmse_limit"):
    """The fastest row (``auto`` left out) whose ``metric`` is at most ``error``, or None."""
    ok = [r for r in rows if r["method"] not in _SKIP and r[metric] <= error * (1 + 1e-9)]
    return min(ok, key=lambda r: r["ms"]) if ok else None


def front_time(rows, error: float, metric: str = "rmse_limit") -> float:
    """The Pareto front's time at ``error``: the least ms of the rows (``auto`` left out) whose
    ``metric`` is at most ``error``; inf when none is."""
    ok = [r["ms"] for r in rows if r["method"] not in _SKIP and r[metric] <= error * (1 + 1e-9)]
    return min(ok) if ok else float("inf")


def landing(rows, auto_row: dict, tolerance: float, metric: str = "rmse_limit") -> dict:
    """``{ms, error, front_ms, ratio, meets}`` of one ``auto`` row on its scene's ``rows``:
    its time over the front's time at the error it reached, and whether it met ``tolerance``."""
    f = front_time(rows, auto_row[metric], metric)
    return {
        "ms": auto_row["ms"],
        "error": auto_row[metric],
        "front_ms": f,
        "ratio": auto_row["ms"] / f if math.isfinite(f) else float("nan"),
        "meets": auto_row[metric] <= tolerance,
    }
