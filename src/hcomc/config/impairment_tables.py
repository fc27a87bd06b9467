"""The ``[v2x]``, ``[[faults]]`` and ``[shield]`` tables of a scenario or corridor config.

A run's V2X channel, the faults injected into it and its safety shield, as frozen pydantic
tables (unknown keys rejected; units and allowed ranges in the field descriptions). Their
defaults are the nominal run: an ideal channel, no fault, no shield; a run with all three at
their defaults is bit for bit the run without them. The robustness layer
(:mod:`hcomc.robustness`) acts them out through the engine's listener interface. Named
presets (:data:`CHANNELS`, :data:`FAULTS`) are the settings the robustness campaign uses; a
``[[faults]]`` entry may name a preset of :data:`FAULTS` instead of giving its keys
(``faults = ["brake-vmf"]``).
"""

from __future__ import annotations

import math
from typing import Any, Literal

from pydantic import Field, model_validator

from hcomc.config.frozen_model import FrozenModel

__all__ = [
    "CHANNELS",
    "FAULTS",
    "MAX_FAULTS",
    "ChannelParams",
    "FaultParams",
    "ShieldParams",
    "fault_entries",
    "impairing_key",
    "nominal",
]

MAX_FAULTS = 16
"""Most faults one run may inject."""


class ChannelParams(FrozenModel):
    """The V2X channel between the vehicles and the merge controller (a roadside unit).

    Every vehicle's state (x, v, a, lane) is broadcast ``update_rate`` times a second and
    arrives ``latency + U(0, jitter)`` seconds later, unless lost: independently with
    probability ``loss``, or (``loss_model = "gilbert_elliott"``) in bursts of a two-state
    Gilbert-Elliott chain per sender with the same stationary loss rate and a mean burst of
    ``mean_burst`` messages. Messages of vehicles farther than ``range`` from the roadside
    unit (at the acceleration-lane start) never arrive. A plan reaches its vehicles the same
    way: after one latency draw, or never.
    """

    update_rate: float = Field(10.0, gt=0, le=100, description="broadcasts per second [Hz]")
    latency: float = Field(0.0, ge=0, le=5, description="fixed delay of every message [s]")
    jitter: float = Field(
        0.0, ge=0, le=5, description="extra delay, uniform between 0 and jitter [s]"
    )
    loss: float = Field(0.0, ge=0, lt=1, description="stationary share of lost messages [-]")
    loss_model: Literal["independent", "gilbert_elliott"] = Field(
        "independent", description="'independent' losses, or bursts of a Gilbert-Elliott chain"
    )
    mean_burst: float = Field(
        5.0, ge=1, le=1000, description="Gilbert-Elliott: mean length of a loss burst [messages]"
    )
    range: float = Field(
        math.inf, gt=0, description="communication range around the roadside unit [m]"
    )
    max_age: float = Field(
        2.0, gt=0, le=60, description="the controller forgets a state older than this [s]"
    )
    stale_after: float = Field(
        0.5,
        gt=0,
        le=60,
        description="a CAV whose CAV leader's newest message is older than this drives on its "
        "own sensors with the degraded time headway [s]",
    )
    degraded_time_headway: float = Field(
        1.5, gt=0, le=10, description="time headway T of a CAV without its leader's messages [s]"
    )

    @property
    def ideal(self) -> bool:
        """Whether every message arrives at once (the nominal run)."""
        return self.latency == 0 and self.jitter == 0 and self.loss == 0 and math.isinf(self.range)

    @property
    def period(self) -> float:
        """Time between two broadcasts of one vehicle [s]."""
        return 1.0 / self.update_rate


class FaultParams(FrozenModel):
    """One injected fault, with its seeded timing (drawn from the run's seed, never from the
    traffic's random stream, so the traffic before the fault is the nominal one).

    * ``none``: the nominal run.
    * ``emergency_brake``: the key vehicle ``role`` brakes at ``decel`` (0, the default: the
      Eq. 15 emergency deceleration a_merg of the scenario's control table) from ``U(delay_min,
      delay_max)`` seconds after the ramp vehicle entered the control zone, for ``U(duration_min,
      duration_max)`` seconds (or until it stands), then drives on by its model.
    * ``aggressive_hdv``: every human-driven key vehicle drives with ``time_headway``,
      ``min_gap`` and ``max_accel`` (short headways; unknown to the controller, which predicts
      with the nominal HDV model).
    * ``ignore_command``: the vehicle the first plan commands to cooperate (VR when it
      commands none) keeps driving by its own model and starts no commanded lane change.
    * ``sensor_dropout``: the key vehicle ``role``, if a CAV, loses its sensors for the same
      seeded window as ``emergency_brake``: it holds the acceleration it had when they failed
      (it no longer reacts to the traffic or to its plan), then drives on by its model.
    * ``sensor_noise``: the key vehicle ``role``, if a CAV, measures its leader with a faulty
      sensor during the same seeded window: it drives by its car-following model (Eq. 3) on a
      gap and a leader speed with Gaussian errors of ``gap_noise`` and ``speed_noise``, drawn
      anew every step (no plan, no lane change of its own in the window).
    * ``distracted_hdv``: every human-driven key vehicle is distracted during the same seeded
      window: its car following (Eq. 1) acts on the traffic as it was ``distracted_delay``
      seconds ago — the leader too, so a vehicle that merged in front of it within that time
      is not yet seen — with a relative gap error ``distracted_gap_error`` (Eq. 2's
      ``s exp(V_s w)``, ``w`` an Ornstein-Uhlenbeck process of the scenario's correlation
      time); it makes no lane change of its own in the window.
    * ``stalled_vehicle``: a broken-down car stands on the acceleration lane of on-ramp
      ``ramp`` (0: the road's first, counted downstream), its front ``position`` metres past
      the lane's start, for the whole run (the timing keys do not apply). It is no ramp
      vehicle: no controller plans for it and it never merges. The engine's vehicles see it
      as they see any vehicle; for the ramp vehicles behind it the acceleration lane ends at
      its rear (they merge before it, or stop behind it and wait for a gap), while the
      road the controllers are given is the road as built (:mod:`hcomc.sim.stalled`).
    """

    kind: Literal[
        "none",
        "emergency_brake",
        "aggressive_hdv",
        "ignore_command",
        "sensor_dropout",
        "sensor_noise",
        "distracted_hdv",
        "stalled_vehicle",
    ] = Field("none", description="what the fault does (class docstring); 'none' = nothing")
    role: Literal["vmf", "vmc", "vmr", "vnf", "vnr"] = Field(
        "vmf", description="emergency_brake, sensor_dropout, sensor_noise: the key vehicle"
    )
    decel: float = Field(
        0.0, ge=0, le=15,
        description="emergency_brake: deceleration [m/s^2]; 0 = the scenario's a_merg "
        "(control.safety_emergency_decel)",
    )  # fmt: skip
    delay_min: float = Field(0.0, ge=0, le=600, description="earliest start after VR's entry [s]")
    delay_max: float = Field(6.0, ge=0, le=600, description="latest start after VR's entry [s]")
    duration_min: float = Field(1.0, gt=0, le=600, description="shortest braking [s]")
    duration_max: float = Field(4.0, gt=0, le=600, description="longest braking [s]")
    time_headway: float = Field(0.6, gt=0, le=10, description="aggressive_hdv: T [s]")
    min_gap: float = Field(0.5, ge=0, le=20, description="aggressive_hdv: s0 [m]")
    max_accel: float = Field(2.5, gt=0, le=10, description="aggressive_hdv: a [m/s^2]")
    gap_noise: float = Field(
        2.0, ge=0, le=50, description="sensor_noise: standard deviation of the measured gap [m]"
    )
    speed_noise: float = Field(
        1.0, ge=0, le=20, description="sensor_noise: standard deviation of the leader's speed [m/s]"
    )
    distracted_delay: float = Field(
        2.0, ge=0, le=10, description="distracted_hdv: age of what the driver acts on [s]"
    )
    distracted_gap_error: float = Field(
        0.2, ge=0, le=1, description="distracted_hdv: V_s, relative gap-estimation error [-]"
    )
    position: float = Field(
        100.0, gt=0, le=10_000,
        description="stalled_vehicle: its front bumper's distance past the acceleration "
        "lane's start [m]; at most the lane's length, at least its length plus the room a "
        "vehicle stopped before it needs to steer around it (24 m among 5 m cars)",
    )  # fmt: skip
    ramp: int = Field(
        0, ge=0, le=63, description="stalled_vehicle: which on-ramp (0: the first) [-]"
    )

    @model_validator(mode="after")
    def _ordered(self) -> FaultParams:
        if self.delay_min > self.delay_max or self.duration_min > self.duration_max:
            raise ValueError(
                f"need delay_min <= delay_max and duration_min <= duration_max, got "
                f"{self.delay_min}, {self.delay_max}, {self.duration_min}, {self.duration_max}"
            )
        return self

    @property
    def nominal(self) -> bool:
        """Whether this entry injects nothing (kind 'none')."""
        return self.kind == "none"


class ShieldParams(FrozenModel):
    """The safety shield: an RSS safe-distance rule (Shalev-Shwartz, Shammah & Shashua 2017,
    Definition 1) checked on the true state before a commanded vehicle's acceleration or a
    commanded lane change acts (:mod:`hcomc.robustness.shield`)."""

    enabled: bool = Field(False, description="check every commanded vehicle every step")
    response_time: float = Field(0.3, ge=0, le=3, description="rho, response time [s]")
    accel_max: float = Field(
        1.4, ge=0, le=10, description="a_max,accel, worst acceleration during rho [m/s^2]"
    )
    brake_min: float = Field(
        4.0, gt=0, le=15, description="b_min,brake, the braking the shield commands [m/s^2]"
    )
    brake_max: float = Field(
        7.5, gt=0, le=15, description="b_max,brake, the leader's worst braking (a_merg) [m/s^2]"
    )


CHANNELS: dict[str, ChannelParams] = {
    "ideal": ChannelParams(),
    "lat100-loss10": ChannelParams(latency=0.1, loss=0.1),
    "lat300-loss30-bursty": ChannelParams(latency=0.3, loss=0.3, loss_model="gilbert_elliott"),
}
"""The campaign's channel settings: ideal, 100 ms + 10 % independent loss, 300 ms + 30 %
bursty loss (mean burst 5 messages = 0.5 s)."""

FAULTS: dict[str, FaultParams] = {
    "none": FaultParams(),
    "brake-vmf": FaultParams(kind="emergency_brake", role="vmf"),
    "brake-vnf": FaultParams(kind="emergency_brake", role="vnf"),
    "aggressive-hdv": FaultParams(kind="aggressive_hdv"),
    "ignore-command": FaultParams(kind="ignore_command"),
    "dropout-vmc": FaultParams(kind="sensor_dropout", role="vmc"),
    "noise-vmc": FaultParams(kind="sensor_noise", role="vmc"),
    "distracted-hdv": FaultParams(kind="distracted_hdv"),
    "stalled": FaultParams(kind="stalled_vehicle"),
}
"""The campaign's fault catalogue."""


def fault_entries(value: Any) -> Any:
    """A ``faults`` list as validation takes it: an entry that is a string names a preset of
    :data:`FAULTS` (``"brake-vmf"``); tables pass through. Anything else is left to the
    validator, which names what is wrong."""
    if not isinstance(value, list | tuple):
        return value
    for entry in value:
        if isinstance(entry, str) and entry not in FAULTS:
            raise ValueError(
                f"fault '{entry}' is not a preset; allowed: {', '.join(FAULTS)}, or a table "
                "with 'kind' and its parameters"
            )
    return [FAULTS[e].model_dump() if isinstance(e, str) else e for e in value]


def nominal(v2x: ChannelParams, faults: tuple[FaultParams, ...], shield: ShieldParams) -> bool:
    """Whether a run with these tables is the nominal run: ideal channel, no fault, no shield."""
    return impairing_key(v2x, faults, shield) is None


def impairing_key(
    v2x: ChannelParams, faults: tuple[FaultParams, ...], shield: ShieldParams
) -> str | None:
    """The first table that makes a run other than nominal (``v2x``, ``faults`` or
    ``shield.enabled``), or None."""
    if not v2x.ideal:
        return "v2x"
    if not all(f.nominal for f in faults):
        return "faults"
    return "shield.enabled" if shield.enabled else None
