"""Vehicle tracks of a run in CommonRoad's conventions: body centre, heading, speed along it.

hcomc's reference point is the centre of the **front bumper** (``x`` along the road, ``y``
lateral, :mod:`hcomc.equations.collision`), its speed ``v`` the longitudinal one (``x``
advances by ``v`` per second; a lane change moves ``y`` along a quintic path in ``x``,
so the heading is ``h = atan(dy/dx)``). CommonRoad places a vehicle's rectangle at its
**centre** with the orientation of its body and gives the speed along that orientation.
:func:`body_centre` converts, in closed form:

.. math::

    c = (x - \\tfrac L2 \\cos h,\\; y - \\tfrac L2 \\sin h), \\qquad
    v_{\\parallel} = v / \\cos h, \\qquad a_{\\parallel} = a / \\cos h ,

so the rectangle is the one of hcomc's Eq. 7 collision test. ``a / cos h`` neglects the
change of the heading within a step (|h| stays below a few degrees in a lane change).

A :class:`Track` is one vehicle's states at consecutive CommonRoad time steps; time step k is
the exported run's first row plus k rows. :func:`log_tracks` reads a
:class:`~hcomc.sim.log.SimulationLog`; a vehicle seen at one row only has no trajectory in
CommonRoad (at least one state after the initial one) and is left out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from hcomc.road import Kind, Lane
from hcomc.sim.log import SimulationLog

__all__ = ["BodyStates", "Track", "body_centre", "first_ramp_vehicle", "log_tracks"]


@dataclass(frozen=True, slots=True)
class BodyStates:
    """States of the body centre: position [m], orientation [rad], speed and acceleration
    along the orientation [m/s, m/s^2]; arrays of one shape."""

    x: np.ndarray
    y: np.ndarray
    orientation: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray


def body_centre(
    x: np.ndarray, y: np.ndarray, heading: np.ndarray, v: np.ndarray, a: np.ndarray,
    length: float | np.ndarray,
) -> BodyStates:  # fmt: skip
    """CommonRoad states of vehicles whose front bumper centre is at ``(x, y)`` [m], with
    heading [rad], longitudinal speed ``v`` [m/s] and acceleration ``a`` [m/s^2] and body
    ``length`` [m] (module docstring)."""
    h = np.asarray(heading, dtype=np.float64)
    # the C library's cosine and sine (math), not numpy's, whose last bit depends on the CPU
    cos = np.vectorize(math.cos, otypes=[np.float64])(h)
    sin = np.vectorize(math.sin, otypes=[np.float64])(h)
    half = 0.5 * np.asarray(length, dtype=np.float64)
    return BodyStates(
        x=np.asarray(x, dtype=np.float64) - half * cos,
        y=np.asarray(y, dtype=np.float64) - half * sin,
        orientation=h,
        velocity=np.asarray(v, dtype=np.float64) / cos,
        acceleration=np.asarray(a, dtype=np.float64) / cos,
    )


@dataclass(frozen=True, slots=True)
class Track:
    """One vehicle: hcomc id, body [m], CommonRoad obstacle class, and its states from time
    step ``first_step`` on, one per step."""

    vehicle: int
    cav: bool
    length: float
    width: float
    vehicle_class: str  # CommonRoad obstacle type: "car", "truck", "bus", "motorcycle"
    first_step: int
    states: BodyStates

    @property
    def n_states(self) -> int:
        """Number of states (initial state included)."""
        return int(self.states.x.size)

    @property
    def last_step(self) -> int:
        """Time step of the last state."""
        return self.first_step + self.n_states - 1

    def from_step(self, step: int) -> Track | None:
        """The track from time step ``step`` on, renumbered so that ``step`` becomes 0; None
        if fewer than two states are left (no trajectory)."""
        skip = max(step - self.first_step, 0)
        if self.n_states - skip < 2:
            return None
        s = self.states
        cut = BodyStates(s.x[skip:], s.y[skip:], s.orientation[skip:], s.velocity[skip:],
                         s.acceleration[skip:])  # fmt: skip
        return replace(self, first_step=self.first_step + skip - step, states=cut)


def log_tracks(log: SimulationLog) -> tuple[Track, ...]:
    """One track per vehicle of ``log`` on the road at two logged rows or more (time step =
    row), in vehicle order."""
    n = log.n_recorded
    active = np.asarray(log.active[:n])
    cells = {name: np.asarray(getattr(log, name)[:n]) for name in ("x", "y", "heading", "v", "a")}
    tracks = []
    for i in np.flatnonzero(active.sum(axis=0) >= 2).tolist():
        rows = np.flatnonzero(active[:, i])
        if rows[-1] - rows[0] + 1 != rows.size:
            raise ValueError(
                f"vehicle {i} leaves the road and comes back (rows {rows[0]} to {rows[-1]} "
                "with gaps); a CommonRoad trajectory has no gaps"
            )
        length = float(log.length[i])
        x, y, h, v, a = (cells[name][rows, i] for name in ("x", "y", "heading", "v", "a"))
        tracks.append(Track(
            vehicle=i, cav=int(log.kind[i]) == Kind.CAV, length=length,
            width=float(log.width[i]), vehicle_class="car", first_step=int(rows[0]),
            states=body_centre(x, y, h, v, a, length),
        ))  # fmt: skip
    return tuple(tracks)


def first_ramp_vehicle(log: SimulationLog) -> int | None:
    """The merging vehicle VR of a run of the paper's road: the first vehicle logged on the
    ramp lane (the earliest first row; the lowest id among equals); None if there is none."""
    n = log.n_recorded
    active = np.asarray(log.active[:n])
    lanes = np.asarray(log.lane[:n])
    best: tuple[int, int] | None = None
    for i in np.flatnonzero(active.any(axis=0)).tolist():
        row = int(np.argmax(active[:, i]))
        if lanes[row, i] == Lane.RAMP and (best is None or row < best[0]):
            best = (row, i)
    return None if best is None else best[1]
