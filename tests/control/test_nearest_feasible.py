"""The nearest-feasible search of the rule-based baselines: block by block, it returns what
scoring its whole grid at once returns (the first feasible cell in the grid's order) and
scores no more rows than the blocks up to that cell."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from hcomc.control.hierarchical.problem_terms import CONSTRAINTS
from hcomc.control.longitudinal_candidate import SEARCH_BLOCK, nearest_feasible
from search_grid import documented_grid

G_VIRTUAL = CONSTRAINTS.index("virtual_vehicle")
MERGE_X, DURATION, HORIZON, H_MAX = 710.0, 4.0, 6.3, 20.0


class MaskedProblem:
    """A problem whose virtual vehicles are feasible exactly in the cells of ``feasible``
    (by (merge_x, H)); it records the rows it was asked to score."""

    def __init__(self, feasible: set[tuple[float, float]]) -> None:
        self.feasible = feasible
        self.scored: list[np.ndarray] = []

    def evaluate(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        self.scored.append(rows.copy())
        G = np.ones((len(rows), len(CONSTRAINTS)))
        for r, row in enumerate(rows):
            G[r, G_VIRTUAL] = -1.0 if (row[0], row[2]) in self.feasible else 1.0
        return np.zeros((len(rows), 3)), G


def whole_grid(x_last: float) -> list[tuple[float, float]]:
    """The grid searched from the test's candidate up to ``x_last``."""
    return documented_grid(MERGE_X, HORIZON, H_MAX, x_last)


@settings(max_examples=60, deadline=None)
@given(
    x_last=st.integers(0, 1000).map(lambda quarters: MERGE_X + quarters / 4.0),  # 0-250 m
    picks=st.lists(st.floats(0.0, 1.0, exclude_max=True), max_size=4),
    sequence=st.sampled_from([0, 1]),
)
def test_the_search_returns_the_first_feasible_cell_of_the_whole_grid(x_last, picks, sequence):
    grid = whole_grid(x_last)
    feasible = {grid[int(p * len(grid))] for p in picks}
    problem = MaskedProblem(feasible)
    found = nearest_feasible(problem, MERGE_X, DURATION, HORIZON, H_MAX, x_last, sequence)
    first = next((k for k, cell in enumerate(grid) if cell in feasible), None)
    assert found == (None if first is None else grid[first])
    rows = np.concatenate(problem.scored)
    # the cells scored are the grid's, in its order, each once, with the candidate's other values
    assert [(x, h) for x, h in rows[:, [0, 2]]] == grid[: len(rows)]
    assert (rows[:, 1] == DURATION).all()
    assert (rows[:, 3] == 0.0).all()
    assert (rows[:, 4] == sequence).all()
    # blocks of 16, 32, 64, ...: the search stops with the block that holds the first feasible
    sizes = [len(r) for r in problem.scored]
    assert sizes[:-1] == [SEARCH_BLOCK * 2**k for k in range(len(sizes) - 1)]
    if first is None:
        assert len(rows) == len(grid)
    else:
        assert len(rows) - sizes[-1] <= first < len(rows)


def test_an_early_feasible_cell_scores_one_block_of_a_large_grid():
    x_last = MERGE_X + 200.0
    grid = whole_grid(x_last)
    problem = MaskedProblem({grid[3], grid[200]})
    assert len(grid) > 400
    found = nearest_feasible(problem, MERGE_X, DURATION, HORIZON, H_MAX, x_last)
    assert found == grid[3]
    assert [len(r) for r in problem.scored] == [SEARCH_BLOCK]


def test_no_grid_beyond_the_rules_own_cell_scores_nothing():
    problem = MaskedProblem(set())
    assert nearest_feasible(problem, MERGE_X, DURATION, H_MAX, H_MAX, MERGE_X) is None
    assert problem.scored == []
