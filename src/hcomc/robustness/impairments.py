"""A run's V2X channel, injected faults and safety shield, as one step listener.

A config's ``[v2x]``, ``[[faults]]`` and ``[shield]`` tables
(:mod:`hcomc.config.impairment_tables`) become one :class:`Impairments` by
:func:`listeners_of`, which every command that runs a config calls; a nominal config gets
none.

:class:`Impairments` is a :class:`hcomc.interface.listener.StepListener`: given to either
engine (``Simulation(config, seed, listeners=[Impairments(...)])``, or the SUMO
co-simulation's ``SumoSimulation`` alike), it acts on the run between its steps and around
the controller's decisions, through the engine's listener interface only:

* **channel** (:mod:`hcomc.robustness.channel`): the vehicles broadcast their state every
  update period; the controller plans on what was received
  (:meth:`~hcomc.robustness.impairments.Impairments.view`), and its plan is put into force
  when it arrives, or never (:meth:`~hcomc.robustness.impairments.Impairments.send`): a ramp
  vehicle whose plan was lost keeps the plan it had (none: it merges by gap acceptance) and
  is planned again a replan period later
  (:meth:`~hcomc.robustness.impairments.Impairments.decisions_due`); a CAV whose CAV
  leader's messages are older than ``stale_after`` drives with the degraded time headway
  until they are fresh again;
* **fault** (:mod:`hcomc.robustness.faults`), timed from the ramp vehicle's control-zone
  entry (:meth:`~hcomc.robustness.impairments.Impairments.on_key_vehicles`);
* **shield** (:mod:`hcomc.robustness.shield`), on the commanded vehicles before each step.

With the ideal channel, no fault and no shield the run is the engine's nominal run, bit for
bit.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from hcomc._typing import FloatArray, IntArray
from hcomc.config import ScenarioConfig
from hcomc.config.impairment_tables import ChannelParams, FaultParams, ShieldParams, nominal
from hcomc.corridor import Corridor
from hcomc.interface import MergeGroup, MergePlan, TrafficView
from hcomc.interface.listener import ListenedRun, StepListener
from hcomc.road import Kind
from hcomc.robustness.channel import Channel
from hcomc.robustness.faults import Fault, Faults
from hcomc.robustness.run_state import broadcast_state
from hcomc.robustness.shield import Shield
from hcomc.sim.log import EventKind, SimulationLog
from hcomc.sim.neighbours import build_lane_index

__all__ = [
    "SHIELD_ACTIONS",
    "Impairments",
    "impairment_columns",
    "impairment_summary",
    "impairments_in",
    "listeners_of",
]

SHIELD_ACTIONS = ("brake", "hold_change", "release")
"""The shield's overrides, by the ``value`` of their SHIELD events."""


class Impairments(StepListener):
    """The channel, faults and shield of one run (each nominal when not given)."""

    def __init__(
        self,
        channel: ChannelParams | None = None,
        faults: Sequence[FaultParams] = (),
        shield: ShieldParams | None = None,
    ) -> None:
        self.channel_params = channel or ChannelParams()
        self.fault_params = tuple(faults)
        self.shield_params = shield or ShieldParams()
        self._next_plan: dict[int, float] = {}  # VR -> earliest next decision after a loss
        self._pending: list[tuple[float, int, MergePlan]] = []  # (arrival, decision, plan)
        self.plans_lost = 0
        self.degraded_steps = 0
        self.commanded_at: dict[int, frozenset[int]] = {}  # step -> commanded vehicles
        self._faults_noted: set[int] = set()  # faults whose FAULT events are in the log
        self._degraded = np.empty(0, dtype=np.int64)  # CAVs on the degraded headway

    def attach(self, run: ListenedRun) -> None:
        """Set up the channel, fault and shield for ``run``."""
        config = run.config
        self.run = run
        rsu = [ramp.accel_lane_start for ramp in run.ramps]
        self.channel = Channel(self.channel_params, run.x.size, rsu, run.seed)
        self.faults = Faults(self.fault_params, config, run.seed)
        self.faults.stand(run.stalled.tolist(), run.t)
        self.shield = Shield(self.shield_params, config, self.faults)
        self._broadcast_every = max(1, round(self.channel_params.period / run.dt))

    @property
    def fault(self) -> Fault:
        """The run's first fault (what the campaign's one-fault cells report)."""
        return self.faults.first

    # ----------------------------------------------------------------- steps
    def before_step(self, run: ListenedRun, t: float) -> None:
        """Channel (broadcast, deliveries, degraded headways), fault, then the shield on the
        commanded vehicles."""
        if not self.channel_params.ideal:
            if (run.step_index - run.n_warmup) % self._broadcast_every == 0:
                self.channel.broadcast(t, broadcast_state(run))
            self._note_silences(run, *self.channel.deliver(t))
            self._deliver_plans(run, t)
            self._degrade(run, t)
        self.faults.act(run, t)
        self._note_faults(run, t)
        commanded = run.commanded()
        overridden = len(self.shield.overrides)
        self.shield.act(run, t, commanded)
        for o in self.shield.overrides[overridden:]:
            run.note(EventKind.SHIELD, o.vehicle, o.other, SHIELD_ACTIONS.index(o.action))
        if commanded.size:
            self.commanded_at[run.step_index] = frozenset(commanded.tolist())

    def _note_silences(self, run: ListenedRun, vehicles: IntArray, silent_for: FloatArray) -> None:
        """A V2X_SILENT event for each key vehicle (of any merge so far) among ``vehicles``,
        heard again after ``silent_for`` seconds (the other vehicles' silences would swamp
        the log: a lossy channel loses thousands of messages a run)."""
        if not vehicles.size or not run.key_groups:
            return
        keys = np.concatenate([g.as_array() for g in run.key_groups.values()])
        for i, gap in zip(vehicles.tolist(), silent_for.tolist(), strict=True):
            if i in keys:
                run.note(EventKind.V2X_SILENT, i, -1, gap)

    def _note_faults(self, run: ListenedRun, t: float) -> None:
        """A FAULT event per vehicle of each fault that began to act by ``t``."""
        for k, fault in enumerate(self.faults.each):
            if k not in self._faults_noted and fault.vehicles and fault.start <= t + 1e-9:
                self._faults_noted.add(k)
                for i in fault.vehicles:
                    run.note(EventKind.FAULT, i, -1, k)

    def on_key_vehicles(self, run: ListenedRun, group: MergeGroup, t: float) -> None:
        """Start the faults' clocks at the first ramp vehicle's control-zone entry."""
        self.faults.on_entry(run, group, t)

    # ------------------------------------------------------------- decisions
    def decisions_due(self, run: ListenedRun, t: float) -> Sequence[int]:
        """Ramp vehicles whose last plan was lost and that are due for a new one."""
        due = [vr for vr, when in self._next_plan.items() if when <= t + 1e-9]
        return [vr for vr in due if run.may_execute(vr)]

    def holds(self, vr: int) -> bool:
        """Whether VR's last plan is on its way."""
        return any(p.group.vr == vr for _, _, p in self._pending)

    def view(self, run: ListenedRun, view: TrafficView) -> TrafficView:
        """What the channel delivered (the true state on the ideal channel)."""
        return view if self.channel_params.ideal else self.channel.view(view)

    def send(self, run: ListenedRun, plan: MergePlan, ident: int, t: float) -> bool:
        """Into force now (ideal channel), when it arrives, or never (lost: its VR is
        planned again a replan period later)."""
        self._next_plan.pop(plan.group.vr, None)
        delay = 0.0 if self.channel_params.ideal else self.channel.plan_delay()
        if math.isinf(delay):
            self.plans_lost += 1
            run.note(EventKind.PLAN_LOST, plan.group.vr)
            self._next_plan[plan.group.vr] = t + run.config.control.replan_period
            return False
        if delay == 0.0:
            return True
        self._pending.append((t + delay, ident, plan))
        return False

    def ignores(self, plan: MergePlan) -> frozenset[int]:
        """The vehicles the faults make ignore ``plan``."""
        return frozenset(self.faults.ignores(plan))

    def _deliver_plans(self, run: ListenedRun, t: float) -> None:
        """Put into force the plans that arrived by ``t`` whose VR can still act on them."""
        arrived = [(ident, p) for when, ident, p in self._pending if when <= t + 1e-9]
        self._pending = [item for item in self._pending if item[0] > t + 1e-9]
        for ident, plan in arrived:
            if run.may_execute(plan.group.vr):
                run.execute(plan, ident)

    def _degrade(self, run: ListenedRun, t: float) -> None:
        """CAVs behind a CAV whose newest message is stale drive with the degraded headway
        (those of the last step drive with their own again first); the leaders are looked
        up only when some CAV has been silent that long."""
        kind, T = run.fleet.kind, run.driving.T
        T[self._degraded] = run.fleet.T[self._degraded]
        self._degraded = self._degraded[:0]
        cav = run.active & (kind == Kind.CAV)
        if not (cav & (t - self.channel.heard > self.channel_params.stale_after)).any():
            return
        ids = np.flatnonzero(cav)
        on_road = np.flatnonzero(run.active)
        index = build_lane_index(on_road, run.lane[on_road], run.x[on_road])
        leaders = index.leader_of(np.searchsorted(on_road, ids))
        has = leaders >= 0
        stale = np.zeros(ids.size, dtype=bool)
        stale[has] = (kind[leaders[has]] == Kind.CAV) & (
            t - self.channel.heard[leaders[has]] > self.channel_params.stale_after
        )
        self._degraded = ids[stale]
        T[self._degraded] = self.channel_params.degraded_time_headway
        self.degraded_steps += int(stale.sum())

    # --------------------------------------------------------------- results
    def summary(self) -> dict[str, Any]:
        """What the channel, the faults and the shield did in the run: plans lost, steps a
        CAV drove with the degraded headway, the shield's overrides by action, and each
        fault's kind, vehicles and start [s] (None: it found no vehicle or never began);
        JSON-ready."""
        counts = self.shield.counts()
        return {
            "plans_lost": self.plans_lost, "degraded_steps": self.degraded_steps,
            **{f"shield_{action}": counts[action] for action in SHIELD_ACTIONS},
            "faults": [{"kind": f.kind, "vehicles": [int(i) for i in f.vehicles],
                        "start": f.start if f.vehicles and math.isfinite(f.start) else None}
                       for f in self.faults.each if f.kind != "none"],
        }  # fmt: skip

    def collisions_commanded(self, log: SimulationLog) -> int:
        """COLLISION events of the run's ``log`` with a vehicle that a live plan commanded in
        that step."""
        count = 0
        for e in log.events_of(EventKind.COLLISION):
            step = round((float(e["t"]) + self.run.config.warmup) / self.run.dt)
            commanded = self.commanded_at.get(step, frozenset()) | self.commanded_at.get(
                step - 1, frozenset()
            )
            count += int(int(e["vehicle"]) in commanded or int(e["other"]) in commanded)
        return count


def listeners_of(config: ScenarioConfig | Corridor) -> list[StepListener]:
    """The listeners a run of ``config`` (a scenario or a corridor) needs: one
    :class:`Impairments` of its ``[v2x]``, ``[[faults]]`` and ``[shield]`` tables, none for a
    nominal config (whose run is then the engine's own, bit for bit)."""
    if nominal(config.v2x, config.faults, config.shield):
        return []
    return [Impairments(config.v2x, config.faults, config.shield)]


def impairments_in(listeners: Sequence[StepListener]) -> Impairments | None:
    """The :class:`Impairments` among a run's ``listeners``, if any."""
    return next((x for x in listeners if isinstance(x, Impairments)), None)


def impairment_summary(listeners: Sequence[StepListener]) -> dict[str, Any]:
    """``{"impairments": ...}`` (:meth:`Impairments.summary`) for a run with impairments
    among its ``listeners``, ``{}`` for one without: what a command's summary adds."""
    impaired = impairments_in(listeners)
    return {} if impaired is None else {"impairments": impaired.summary()}


def impairment_columns(impaired: Impairments | None) -> dict[str, Any]:
    """A results row's columns of what ``impaired`` did (:meth:`Impairments.summary`, the
    faults as space-separated ``fault_kinds``, ``fault_vehicles`` and ``fault_starts``), or
    none for a run without impairments."""
    if impaired is None:
        return {}
    summary = impaired.summary()
    faults = summary.pop("faults")
    return {
        **summary,
        "fault_kinds": " ".join(f["kind"] for f in faults),
        "fault_vehicles": " ".join(",".join(map(str, f["vehicles"])) or "-" for f in faults),
        "fault_starts": " ".join(
            "-" if f["start"] is None else f"{f['start']:.2f}" for f in faults
        ),
    }
