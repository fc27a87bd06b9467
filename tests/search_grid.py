"""The nearest-feasible search grid of the rule-based baselines in its documented order,
written out independently of :func:`hcomc.control.longitudinal_candidate.nearest_feasible`
(an oracle for the tests)."""

from __future__ import annotations

from hcomc.control.longitudinal_candidate import HORIZON_STEP, POSITION_STEP


def documented_grid(
    merge_x: float, horizon: float, h_max: float, x_last: float
) -> list[tuple[float, float]]:
    """The (merge_x, H) cells: each merge position from ``merge_x`` by POSITION_STEP up to
    ``x_last`` (and ``x_last`` itself), each with H from ``horizon`` by HORIZON_STEP up to
    ``h_max`` (and ``h_max`` itself); the rule's own cell, the first, left out."""
    positions = [merge_x + i * POSITION_STEP for i in range(400)
                 if merge_x + i * POSITION_STEP <= x_last]  # fmt: skip
    positions += [x_last] if positions[-1] < x_last else []
    horizons = [horizon + k * HORIZON_STEP for k in range(400)
                if horizon + k * HORIZON_STEP <= h_max]  # fmt: skip
    horizons += [h_max] if horizons[-1] < h_max else []
    return [(x, h) for x in positions for h in horizons][1:]
