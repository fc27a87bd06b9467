"""The V2X channel: what the merge controller knows of the traffic, and when plans arrive.

Every vehicle broadcasts its state every ``1 / update_rate`` seconds (from the end of the
warm-up). A broadcast is lost (independently, or in Gilbert-Elliott bursts per sender),
otherwise it arrives after ``latency + U(0, jitter)`` seconds; the roadside units (one at
each on-ramp's acceleration-lane start, networked with the controller) hear only vehicles
within ``range`` of one of them, a
following vehicle hears its leader at any distance. What arrived is all the controller
sees: for each vehicle its newest received state and that state's age (a vehicle not heard
for ``max_age`` seconds, or never, is absent). A plan is one downlink message: it arrives
after one latency draw, or is lost. The channel draws from its own generator (derived from
the run's seed), so the traffic's random stream is the nominal one.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.config.impairment_tables import ChannelParams
from hcomc.interface import TrafficView

__all__ = ["Channel", "ChannelView", "GilbertElliott"]

_EPS_T = 1e-9  # [s] arrival times are sums of step times: compare with a tolerance

CHANNEL_STREAM = 0x5632_5800
"""Spawn key of the channel's generator: ``SeedSequence([seed, CHANNEL_STREAM])``."""


@dataclass(frozen=True, slots=True)
class ChannelView(TrafficView):
    """A :class:`~hcomc.interface.TrafficView` of received states: ``x, v, a, lane,
    changing`` are each vehicle's newest received values, ``active`` whether any arrived,
    and ``age`` [s] how old they are (``inf``: not heard within ``max_age``)."""

    age: FloatArray = field(default_factory=lambda: np.empty(0))


class GilbertElliott:
    """Loss of a two-state Markov chain per sender (Gilbert 1960, Elliott 1963): a message
    sent in the bad state is lost, in the good state delivered. With a stationary loss
    rate ``p_loss`` and a mean burst of ``b`` messages the chain leaves the bad state with
    ``r = 1 / b`` and enters it with ``p = p_loss r / (1 - p_loss)`` (stationary share of the
    bad state ``p / (p + r) = p_loss``). Independent loss is the chain with ``b = 1 /
    (1 - p_loss)`` (``p + r = 1``)."""

    def __init__(self, n: int, p_loss: float, mean_burst: float, rng: np.random.Generator):
        self.r = 1.0 / mean_burst
        self.p = p_loss * self.r / (1.0 - p_loss) if p_loss > 0 else 0.0
        self.rng = rng
        self.bad: BoolArray = rng.random(n) < p_loss  # start in the stationary distribution

    def lost(self) -> BoolArray:
        """Advance every sender's chain by one message; whether each message is lost."""
        u = self.rng.random(self.bad.size)
        self.bad = np.where(self.bad, u >= self.r, u < self.p)
        return self.bad.copy()


@dataclass
class _Broadcast:
    sent: float
    arrive: FloatArray  # (N,) arrival at the roadside unit, inf if lost or out of range
    arrive_v2v: FloatArray  # (N,) arrival at other vehicles, inf if lost
    state: dict[str, np.ndarray]
    first: float = 0.0  # the earliest arrival still to come (inf: none)

    def __post_init__(self) -> None:
        self.update_first()

    def update_first(self) -> None:
        """Set :attr:`first` from the arrivals still to come."""
        self.first = min(self.arrive.min(initial=math.inf), self.arrive_v2v.min(initial=math.inf))


class Channel:
    """Broadcasts, arrivals and the controller's knowledge for one run of ``n`` vehicles."""

    def __init__(self, params: ChannelParams, n: int, rsu_x: Sequence[float], seed: int) -> None:
        self.params, self.rsu_x = params, np.asarray(rsu_x, dtype=np.float64)
        self.rng = np.random.default_rng(np.random.SeedSequence([seed, CHANNEL_STREAM]))
        burst = params.mean_burst if params.loss_model == "gilbert_elliott" else None
        indep = 1.0 / (1.0 - params.loss)
        self.loss = GilbertElliott(n, params.loss, burst or indep, self.rng)
        self.downlink = GilbertElliott(1, params.loss, burst or indep, self.rng)
        self._pending: list[_Broadcast] = []
        self.known: dict[str, np.ndarray] = {}
        self.sent = np.full(n, -math.inf)  # send time of the newest state the RSU received
        self.heard = np.full(n, -math.inf)  # ... that other vehicles received
        self.broadcasts = self.received = 0

    def delay(self, size: int) -> FloatArray:
        """Delivery delays [s] of ``size`` messages: latency plus uniform jitter."""
        return self.params.latency + self.params.jitter * self.rng.random(size)

    def broadcast(self, t: float, state: dict[str, np.ndarray]) -> None:
        """Every vehicle with ``state["active"]`` sends ``state`` at ``t``."""
        active = state["active"]
        lost = self.loss.lost()
        arrive_v2v = np.where(active & ~lost, t + self.delay(active.size), math.inf)
        gap = np.abs(state["x"][:, None] - self.rsu_x).min(axis=1, initial=math.inf)
        near = gap <= self.params.range  # a road without on-ramps has no roadside unit
        arrive = np.where(near, arrive_v2v, math.inf)
        self.broadcasts += int(active.sum())
        self._pending.append(
            _Broadcast(t, arrive, arrive_v2v, {k: v.copy() for k, v in state.items()})
        )
        if not self.known:  # the channel opens: nobody is overdue before its first period
            self.known = {k: np.zeros_like(v) for k, v in state.items()}
            self.heard[:] = t

    def deliver(self, t: float) -> tuple[IntArray, FloatArray]:
        """Apply every message that has arrived by ``t`` (a newer state replaces an older);
        returns the vehicles whose newest state arrived after a silence longer than
        ``stale_after`` and the time between the broadcasts of their last two received
        states [s]."""
        keep, silent, silent_for = [], [], []
        for msg in self._pending:
            if msg.first > t + _EPS_T:  # nothing of it arrives yet
                keep.append(msg)
                continue
            arrived = msg.arrive <= t + _EPS_T  # a state older than one received is dropped
            got = arrived & (msg.sent > self.sent)
            if got.any():
                gap = msg.sent - self.sent
                long = got & (gap > self.params.stale_after) & np.isfinite(gap)
                silent.append(np.flatnonzero(long))
                silent_for.append(gap[long])
                for name, values in msg.state.items():
                    self.known[name][got] = values[got]
                self.sent[got] = msg.sent
                self.received += int(got.sum())
            msg.arrive[arrived] = math.inf
            arrived = msg.arrive_v2v <= t + _EPS_T
            self.heard[arrived & (msg.sent > self.heard)] = msg.sent
            msg.arrive_v2v[arrived] = math.inf
            msg.update_first()
            if math.isfinite(msg.first):
                keep.append(msg)
        self._pending = keep
        if not silent:
            return np.empty(0, dtype=np.int64), np.empty(0)
        return np.concatenate(silent), np.concatenate(silent_for)

    def view(self, true_view: TrafficView) -> ChannelView:
        """What the controller knows at ``true_view.t``: the newest received states."""
        t = true_view.t
        heard = t - self.sent <= self.params.max_age + _EPS_T
        if self.known:
            state = {**self.known, "active": heard & self.known["active"]}
        else:
            state = {"x": true_view.x, "v": true_view.v, "a": true_view.a,
                     "lane": true_view.lane, "active": np.zeros_like(true_view.active),
                     "changing": true_view.changing}  # fmt: skip
        base = TrafficView.snapshot(
            t, state, true_view.fleet, true_view.config, true_view.plans, true_view.ramp
        )
        age = np.where(heard, t - self.sent, math.inf)
        age.flags.writeable = False
        fields = {f.name: getattr(base, f.name) for f in dataclasses.fields(TrafficView)}
        return ChannelView(**fields, age=age)

    def plan_delay(self) -> float:
        """When a plan sent now arrives [s from now], ``inf`` if it is lost."""
        if self.downlink.lost()[0]:
            return math.inf
        return float(self.delay(1)[0])
