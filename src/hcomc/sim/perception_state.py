"""The HDVs' perception state of a run: the ring buffers of past states that the reaction
delays read and each driver's estimation-error processes, sized and scaled from the run's
:class:`~hcomc.config.HDVParams`.

The compiled reading of that state (paper Eq. 2) is :mod:`hcomc.sim.perception`'s; this
Python side builds it from the configuration, so that the kernels do not import it.

**Random streams.** With estimation errors on, the perception takes one fixed-size draw from
the run's generator (two 64-bit words, whatever the number of vehicles), the entropy of a
:class:`numpy.random.SeedSequence` whose children ``(0,)`` and ``(1,)`` draw the initial
``w_gap`` and ``w_ttc`` (one standard normal per vehicle, in release order). The per-step
innovations then come from the run's generator itself, each step drawing ``(2, m)`` standard
normals for the ``m`` vehicles due by its time
(:func:`hcomc.sim.step.loop.draw_innovations`; :meth:`Perception.advance_errors` is the same
step in Python). So a shorter run of a seed perceives exactly as the first vehicles of a
longer one do up to its end, and a run without its ramp vehicles (the undisturbed twin) draws
the same. Without estimation errors nothing is drawn.
"""

from __future__ import annotations

import math

import numpy as np

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.config import HDVParams
from hcomc.equations.perception import ErrorScales
from hcomc.sim.perception import (
    Estimates,
    EstimationErrors,
    History,
    advance_errors_of,
    perceive_into,
)


class Perception:
    """Ring buffer of past states plus the HDVs' estimation-error processes."""

    def __init__(
        self, params: HDVParams, is_hdv: BoolArray, dt: float, rng: np.random.Generator
    ) -> None:
        n = is_hdv.size
        self.dt = dt
        self.params = params
        self.is_hdv = is_hdv
        lags = [
            params.reaction_time_gap,
            params.reaction_time_speed,
            params.reaction_time_approach,
        ]
        self.size = int(np.floor(max(lags) / dt + 1e-9)) + 2
        self.x_hist = np.zeros((self.size, n))
        self.v_hist = np.zeros((self.size, n))
        self.errors = params.estimation_errors and (
            params.gap_error > 0 or params.inverse_ttc_error > 0
        )
        if self.errors:
            # a fixed amount of the run's generator, whatever n (Random streams, module doc)
            entropy = rng.integers(2**64, size=2, dtype=np.uint64)
            self.w_gap = _initial_errors(entropy, _W_GAP, n)
            self.w_ttc = _initial_errors(entropy, _W_TTC, n)
        else:
            self.w_gap, self.w_ttc = np.zeros(n), np.zeros(n)
        self.decay = math.exp(-dt / params.error_correlation_time)  # the C library's, not numpy's
        self.kick = math.sqrt(2.0 * dt / params.error_correlation_time)

    def fill(self, ids: IntArray, x: FloatArray, v: FloatArray) -> None:
        """Initialise the history of newly released vehicles with their current state."""
        self.x_hist[:, ids] = x[ids]
        self.v_hist[:, ids] = v[ids]

    def push(self, step: int, x: FloatArray, v: FloatArray) -> None:
        """Store the state at ``step`` (all vehicles)."""
        row = step % self.size
        self.x_hist[row] = x
        self.v_hist[row] = v

    def advance_errors(
        self, ids: IntArray, rng: np.random.Generator, due: int | None = None
    ) -> None:
        """One OU step of both error processes for the active HDVs ``ids``.

        The step's innovations are ``rng.standard_normal((2, due))``, column i for vehicle i,
        for the ``due`` vehicles due by the step's time (default: all N), even when ``ids`` is
        empty, so the random stream does not depend on which vehicles are active; every id
        must be below ``due``. The compiled step draws the same
        (:func:`hcomc.sim.step.loop.draw_innovations`).
        """
        if not self.errors:
            return
        n = self.is_hdv.size
        m = n if due is None else int(due)
        ids = _ints(ids)
        if not 0 <= m <= n or (ids.size and int(ids.max()) >= m):
            raise ValueError(f"due = {m}: needs 0 <= due <= {n} and every id below it")
        xi = np.zeros((2, n))
        xi[:, :m] = rng.standard_normal((2, m))
        advance_errors_of(self.w_gap, self.w_ttc, ids, self.is_hdv, xi, self.decay, self.kick)

    @property
    def taus(self) -> FloatArray:
        """Reaction times on gap, own speed and approach rate [s]."""
        p = self.params
        return np.array(
            [p.reaction_time_gap, p.reaction_time_speed, p.reaction_time_approach], dtype=float
        )

    def perceive(
        self, step: int, ids: IntArray, leader: IntArray, leader_length: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Delayed, noisy ``(s_est, v, v_leader_est)`` of HDVs ``ids`` behind ``leader``.

        ``leader`` is -1 where there is none: the gap is then infinite.
        """
        p = self.params
        ids, leader = _ints(ids), _ints(leader)
        s, v, vl = np.empty(ids.size), np.empty(ids.size), np.empty(ids.size)
        scales = ErrorScales(p.gap_error, p.inverse_ttc_error, self.errors)
        perceive_into(
            History(self.x_hist, self.v_hist, self.taus, self.dt), step,
            EstimationErrors(self.w_gap, self.w_ttc, scales), ids, leader,
            np.ascontiguousarray(leader_length, dtype=np.float64),
            np.ones(self.is_hdv.size, dtype=np.bool_), Estimates(s, v, vl),
        )  # fmt: skip
        return s, v, vl


# the children of the perception's SeedSequence: the initial error of each process
_W_GAP, _W_TTC = 0, 1


def _initial_errors(entropy: np.ndarray, child: int, n: int) -> FloatArray:
    """w(0) ~ N(0, 1) of n drivers in release order, from the perception's child stream
    ``child``: the first values of a longer run's are a shorter run's."""
    seq = np.random.SeedSequence([int(w) for w in entropy], spawn_key=(child,))
    return np.random.default_rng(seq).standard_normal(n)


def _ints(a: IntArray) -> IntArray:
    return np.ascontiguousarray(a, dtype=np.int64).reshape(-1)
