"""The prediction kernel's shortcuts against independent recomputations.

The rollout counts collisions inside the kernel, takes VNR's longitudinal-mode states from the
no-merge counterfactual and VMC's pre-pass states from one track per mode; each is checked here
against a plain recomputation from the kernel's own outputs or from the one-home functions.
"""

from __future__ import annotations

from dataclasses import replace
from functools import cache

import numpy as np

from hcomc.config import load_config
from hcomc.control.hierarchical.controller import merge_problem
from hcomc.control.hierarchical.problem import MergeProblem
from hcomc.control.hierarchical.problem_terms import AHEAD
from hcomc.control.prediction.passes import vmc_pre_track
from hcomc.control.prediction.population import (
    C_DT,
    G_COLLISION,
    P_LEN,
    P_WID,
    VMC,
    VMR,
    VNF,
    VNR,
    counterfactual,
    rollout,
)
from hcomc.equations.collision import vehicles_collide
from hcomc.equations.virtual_vehicle import cubic_point
from hcomc.sim.engine import Simulation

N_CANDIDATES = 120


@cache
def _problem() -> MergeProblem:
    config = load_config("C1", control={"controller": "hcomc", "replan_period": 0.0})
    sim = Simulation(config, 1)
    assert sim.run_until_plan() is not None
    view, group = sim.requests[0]
    return merge_problem(view, group)


def _rollout(lateral: bool, seed: int = 0, x: np.ndarray | None = None) -> tuple[np.ndarray, ...]:
    """Random candidates of the "ahead" group (key positions ``x`` if given), with the
    counterfactual and the candidates appended to the kernel's outputs."""
    problem = _problem()
    state = replace(problem.states[AHEAD], x=problem.state.x if x is None else x)
    rng = np.random.default_rng(seed)
    xl, xu = problem.xl, problem.xu
    X = xl + rng.random((N_CANDIDATES, 5)) * (xu - xl)
    key = state.vehicles()
    cf = np.stack(counterfactual(key, problem.consts, problem.n_steps))
    out = rollout(
        key, state.starts, X[:, 0].copy(), X[:, 1].copy(), X[:, 2].copy(),
        np.full(N_CANDIDATES, lateral), problem.consts, problem.n_steps, cf,
    )  # fmt: skip
    return (*out, cf, X)


def test_collision_column_counts_every_colliding_pair_step():
    """G_COLLISION equals the exact rectangle test over all pairs and steps of the returned
    trajectories (no prefilter in the oracle); VMR starts half a length into VMC, so that
    collisions do occur."""
    problem = _problem()
    present = problem.states[AHEAD].present
    assert present[VMC]
    assert present[VMR]
    length, width = problem.state.params[:, P_LEN], problem.state.params[:, P_WID]
    x = problem.state.x.copy()
    x[VMR] = x[VMC] - 0.5 * length[VMC]
    total = 0
    for lateral in (False, True):
        xs, ys, _, _, hs, _, _, _, g, *_ = _rollout(lateral, x=x)
        expected = np.zeros(N_CANDIDATES)
        for i in range(6):
            for j in range(i + 1, 6):
                if not (present[i] and present[j]):
                    continue
                hit = vehicles_collide(
                    xs[..., i], ys[..., i], hs[..., i], length[i], width[i],
                    xs[..., j], ys[..., j], hs[..., j], length[j], width[j],
                )  # fmt: skip
                expected += hit.sum(axis=1)
        np.testing.assert_array_equal(g[:, G_COLLISION], expected)
        total += int(expected.sum())
    assert total > 0  # the random candidates do include colliding ones


def test_longitudinal_vnr_is_the_counterfactual_one():
    """In longitudinal mode VNR follows VNF alone: its predicted states are exactly those of
    the no-merge counterfactual; in lateral mode a cooperating VMC moves in ahead of it."""
    xs, _, vs, as_, *_, cf, _ = _rollout(lateral=False)
    for got, ref in ((xs, cf[0]), (vs, cf[1]), (as_, cf[2])):
        np.testing.assert_array_equal(got[:, :, VNR], np.broadcast_to(ref[:, VNR], got.shape[:2]))
    xs_lat, *_ = _rollout(lateral=True)
    assert not np.array_equal(xs_lat[:, :, VNR], xs[:, :, VNR])


def test_vv2_ends_at_vmc_pre_pass_state_at_the_horizon():
    """VV2 ends, at H, in VMC's pre-pass state at the step where the pre-pass stops (the
    first step at or after H, or the window's end): the track of the candidate's mode."""
    problem = _problem()
    s = problem.states[AHEAD]
    *_, vv2, _, X = _rollout(lateral=True, seed=1)
    dt, K = problem.consts[C_DT], problem.n_steps
    for lateral in (False, True):
        track = vmc_pre_track(s.vehicles(), lateral, problem.consts, K)
        assert track.shape == (K + 1, 2)
        np.testing.assert_array_equal(track[0], [s.x[VMC], s.v[VMC]])
    track = vmc_pre_track(s.vehicles(), True, problem.consts, K)
    for c in range(N_CANDIDATES):
        h = X[c, 2]
        k = 0
        while k * dt < h and k < K:
            k += 1
        x_end, v_end, _ = cubic_point(*vv2[c], h)
        np.testing.assert_allclose([x_end, v_end], track[k], rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(vv2[c, :2], [s.x[VNF], s.v[VNF]], rtol=0, atol=0)
