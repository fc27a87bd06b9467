"""One candidate of the prediction (:mod:`hcomc.control.prediction.population`): passes 1
and 2 and the scoring of a candidate plan, the body that the population kernel runs per candidate,
and the single-candidate entry simulated annealing uses.

Simulated annealing asks for one candidate at a time. The population kernel's per-call work
that depends on the planning instant alone — VMC's pre-pass trajectory per mode — is then
prepared once per problem (:func:`vmc_tracks`) and :func:`rollout_into` runs the same body
(:func:`candidate`) on it, so that a row gives the values of the population path bit for bit.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from hcomc._jit import kernel
from hcomc.control.prediction.layout import (
    C_DT,
    G_COLLISION,
    G_EXECUTION,
    G_NO_RETURN,
    G_NOT_MERGED,
    G_OVERRUN,
    G_UNSAFE,
    G_VIRTUAL,
    N_G,
    N_PROGRESS,
    N_ROLES,
    N_STATE,
    VMC,
    VNR,
    VR,
    KeyVehicles,
    Scratch,
    Trajectories,
)
from hcomc.control.prediction.passes import joint_pass, pre_pass, vmc_pre_track, vv0_cubic
from hcomc.control.prediction.scoring import created_pairs_safety, virtual_violation


class RolloutWork(NamedTuple):
    """The arrays one candidate's rollout writes (:func:`rollout_into`), allocated once for
    many rows (:func:`rollout_work`). ``x``, ``v`` and ``a`` are (1, K + 1, 6), the population
    form U_fuel takes."""

    x: np.ndarray  # (1, K + 1, 6) position [m]
    y: np.ndarray  # (K + 1, 6) lateral position [m]
    v: np.ndarray  # (1, K + 1, 6) speed [m/s]
    a: np.ndarray  # (1, K + 1, 6) acceleration [m/s^2]
    heading: np.ndarray  # (K + 1, 6) heading [rad]
    g: np.ndarray  # (N_G,) constraint parts (columns G_*)
    vvs: np.ndarray  # (3, 4) cubic coefficients of VV0, VV1, VV2 (relative time)
    scratch: Scratch  # the passes' scratch space


@kernel
def candidate(
    key: KeyVehicles, starts: np.ndarray, plan: np.ndarray, lateral: bool, consts: np.ndarray,
    cf: np.ndarray, track: np.ndarray, trajectories: Trajectories, g: np.ndarray,
    vvs: np.ndarray, scratch: Scratch,
) -> tuple[int, float, float]:  # fmt: skip
    """Passes 1 and 2 and the scoring of one candidate (``plan``: merge position, VR's
    lane-change duration, horizon H; ``lateral``: its mode variable), the body shared by the
    population kernel (:func:`hcomc.control.prediction.population.rollout`) and the single-row entry
    :func:`rollout_into`.

    ``track`` is VMC's pre-pass trajectory of the candidate's mode (:func:`vmc_tracks`). The
    trajectories go to ``trajectories`` (K + 1, 6) (``y``, ``a``, ``heading`` zeroed by the
    caller), the constraint parts to ``g`` (N_G,) (zeroed by the caller) and the cubics to
    ``vvs`` (3, 4); ``scratch`` is the passes' scratch space. Returns k_merge, U_safe and
    U_eff (see :func:`hcomc.control.prediction.population.rollout`).
    """
    present, cav, coop = key.present, key.cav, key.coop
    horizon = plan[2]
    coop_vmc = bool(coop[VMC] and present[VMC])
    lat, lon = lateral and coop_vmc, (not lateral) and coop_vmc
    vv0_cubic(starts, horizon, cf, consts[C_DT], vvs[0])
    flags = (bool(cav[VR]), lon, lat and bool(coop[VNR] and present[VNR]))
    n_known = pre_pass(key, starts, vvs, plan, flags[0], consts, track, scratch)
    k_merge, g[G_OVERRUN], g[G_COLLISION], u_eff, g[G_NO_RETURN], g[G_EXECUTION] = joint_pass(
        key, vvs, plan, lat, flags, consts, trajectories, scratch, n_known, cf
    )
    g[G_VIRTUAL] = virtual_violation(vvs, horizon, flags, consts)
    if k_merge < 0:
        g[G_NOT_MERGED] = 1.0
        return k_merge, np.inf, u_eff
    X, V, Y = trajectories.x, trajectories.v, trajectories.y
    u_safe = created_pairs_safety(X[k_merge], V[k_merge], Y[k_merge], present, cav, key.params,
                                  lat, consts)  # fmt: skip
    if u_safe == np.inf:
        g[G_UNSAFE] = 1.0
    return k_merge, u_safe, u_eff


@kernel
def mode_index(lateral: bool, coop: np.ndarray, present: np.ndarray) -> int:
    """Index of VMC's pre-pass track for a candidate: 1 when it cooperates laterally."""
    return 1 if lateral and coop[VMC] and present[VMC] else 0


@kernel
def vmc_tracks(key: KeyVehicles, consts: np.ndarray, n_steps: int) -> np.ndarray:
    """VMC's pre-pass trajectories (2, K + 1, 2) of both modes (index 1: lateral), which
    depend on the planning instant alone: computed once per problem for :func:`rollout_into`
    (the population kernel computes them once per call). Without a cooperating VMC only the
    longitudinal track is used, and only it is computed."""
    tracks = np.zeros((2, n_steps + 1, 2))
    tracks[0] = vmc_pre_track(key, False, consts, n_steps)
    if mode_index(True, key.coop, key.present) == 1:
        tracks[1] = vmc_pre_track(key, True, consts, n_steps)
    return tracks


@kernel
def rollout_work(n_steps: int) -> RolloutWork:
    """The arrays of :class:`RolloutWork` for a window of ``n_steps`` steps (uninitialised:
    :func:`rollout_into` zeroes what it accumulates into)."""
    K = n_steps
    return RolloutWork(
        np.empty((1, K + 1, N_ROLES)), np.empty((K + 1, N_ROLES)), np.empty((1, K + 1, N_ROLES)),
        np.empty((1, K + 1, N_ROLES)), np.empty((K + 1, N_ROLES)), np.empty(N_G),
        np.empty((3, 4)),
        Scratch(np.empty((N_STATE, N_ROLES)), np.empty(N_PROGRESS), np.empty((4, N_ROLES)),
                np.empty(max(K, 1))),
    )  # fmt: skip


@kernel
def rollout_into(
    key: KeyVehicles, starts: np.ndarray, plan: np.ndarray, lateral: bool, consts: np.ndarray,
    cf: np.ndarray, tracks: np.ndarray, work: RolloutWork,
) -> tuple[int, float, float]:  # fmt: skip
    """One candidate, as the population kernel (:func:`hcomc.control.prediction.population.rollout`
    with C = 1) computes it, without the per-call work a population needs and a single row
    does not: VMC's pre-pass tracks come precomputed from :func:`vmc_tracks`.

    ``starts`` must be resolved (:func:`~hcomc.control.prediction.population.resolve_starts`);
    ``plan`` (3,) holds the merge position, VR's lane-change duration and the horizon H;
    ``lateral`` the mode. The trajectories, constraint parts and cubics go to the arrays
    ``work`` of :func:`rollout_work` (reused from row to row: a population allocates them
    once); returns k_merge, U_safe and U_eff: the values of the population kernel's row, bit
    for bit."""
    Y, A, HEAD, g, vvs = work.y, work.a, work.heading, work.g, work.vvs
    Y[:], A[:], HEAD[:], g[:], vvs[:] = 0.0, 0.0, 0.0, 0.0, 0.0  # as freshly allocated
    track = tracks[mode_index(lateral, key.coop, key.present)]
    trajectories = Trajectories(work.x[0], Y, work.v[0], A[0], HEAD)
    return candidate(
        key, starts, plan, lateral, consts, cf, track, trajectories, g, vvs, work.scratch
    )
