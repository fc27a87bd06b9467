"""hcomc: cooperative on-ramp merging control in mixed traffic on two-lane highways.

The package implements the HCOMC method (Wang et al., arXiv:2507.11621) on top of a
struct-of-arrays microscopic traffic simulator. Importing it has no side effects.

The names below are its library face, the ones the documentation and examples use: import them
from ``hcomc`` (``from hcomc import Simulation, load_config``), not from the modules that
define them, whose paths may change. Each is loaded on first use, so ``import hcomc`` stays
light (the command line starts without numpy's or numba's import cost).

* scenarios: :func:`load_config`, :class:`ScenarioConfig`, :class:`ConfigError`
* simulation: :class:`Simulation`, :func:`simulate`, :func:`run_ensemble`,
  :class:`SimulationLog`, :class:`Lane`
* controllers: :class:`MergeController` (the protocol a controller of your own meets),
  :class:`MergePlan`, :class:`MergeGroup`, :class:`Mode`, :class:`TrafficView`,
  :func:`make_controller`, :func:`registered`, :class:`InvalidPlan`, :class:`ControllerFailed`
* metrics: :func:`compute_metrics`, :data:`METRICS`
* runs and comparisons: :func:`run` (``hcomc run``), :func:`compare` (``hcomc compare``),
  :class:`ComparisonResult`
* corridors: :func:`load_corridor`, :func:`simulate_corridor`, :func:`sections`,
  :func:`export_corridor` (a SUMO scenario; SUMO's netconvert, extra ``sumo``)
* robustness: :class:`Impairments` (a step listener: V2X channel, fault, shield; given to
  either engine), :data:`CHANNELS`, :data:`FAULTS`, :class:`ChannelParams`,
  :class:`FaultParams`, :class:`ShieldParams`; listeners of your own subclass
  :class:`StepListener`
* learning environments (extra ``envs``): :class:`MergeEnv`, :class:`MergeParallelEnv`,
  :class:`CorridorMergeEnv`, :class:`CorridorParallelEnv` (loading any of them registers
  ``hcomc/Merge-v0`` and ``hcomc/CorridorMerge-v0`` with Gymnasium), the merge controllers as
  policies (:class:`ControllerPolicy`) and :func:`evaluate_policies`, :func:`policy_summary`,
  :func:`compare_policies`
* replay and provenance: :func:`replay` (the browser replay of runs), :func:`git_revision`
* CommonRoad (extra ``commonroad``): :func:`export_commonroad` (a run as a CommonRoad
  scenario), :func:`commonroad_contacts` (which vehicles of a scenario touch when, by
  CommonRoad's collision checker)

A name whose module needs an optional extra that is not installed raises an ImportError
naming the extra to install (``pip install 'hcomc[envs]'``) when it is used, not before.
"""

from importlib import import_module
from importlib.metadata import PackageNotFoundError, version
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from hcomc.commonroad.contacts import commonroad_contacts
    from hcomc.commonroad.export import export_commonroad
    from hcomc.config import ConfigError, ScenarioConfig, load_config
    from hcomc.control.registry import make_controller, registered
    from hcomc.control.validation import ControllerFailed, InvalidPlan
    from hcomc.corridor import load_corridor
    from hcomc.corridor.road import sections
    from hcomc.envs.corridor.env import CorridorMergeEnv
    from hcomc.envs.corridor.multi_agent import CorridorParallelEnv
    from hcomc.envs.merge_env import MergeEnv
    from hcomc.envs.multi_agent import MergeParallelEnv
    from hcomc.envs.policies import (
        ControllerPolicy,
        compare_policies,
        evaluate_policies,
        policy_summary,
    )
    from hcomc.experiments.library import ComparisonResult, compare, run
    from hcomc.interface import MergeController, MergeGroup, MergePlan, Mode, TrafficView
    from hcomc.interface.listener import StepListener
    from hcomc.metrics import METRICS, compute_metrics
    from hcomc.metrics.corridor.run import simulate_corridor
    from hcomc.road import Lane
    from hcomc.robustness import CHANNELS, FAULTS, ChannelParams, FaultParams, ShieldParams
    from hcomc.robustness.impairments import Impairments
    from hcomc.sim.engine import Simulation, simulate
    from hcomc.sim.ensemble import run_ensemble
    from hcomc.sim.log import SimulationLog
    from hcomc.sim.manifest import git_revision
    from hcomc.sumo.corridor import export_corridor
    from hcomc.viz.replay import replay

try:
    __version__ = version("hcomc")
except PackageNotFoundError:  # pragma: no cover - running from a source tree without install
    __version__ = "0.0.0+unknown"

_HOMES: dict[str, str] = {
    "load_config": "hcomc.config",
    "ScenarioConfig": "hcomc.config",
    "ConfigError": "hcomc.config",
    "Simulation": "hcomc.sim.engine",
    "simulate": "hcomc.sim.engine",
    "run_ensemble": "hcomc.sim.ensemble",
    "SimulationLog": "hcomc.sim.log",
    "Lane": "hcomc.road",
    "MergeController": "hcomc.interface",
    "MergePlan": "hcomc.interface",
    "MergeGroup": "hcomc.interface",
    "Mode": "hcomc.interface",
    "TrafficView": "hcomc.interface",
    "make_controller": "hcomc.control.registry",
    "registered": "hcomc.control.registry",
    "InvalidPlan": "hcomc.control.validation",
    "ControllerFailed": "hcomc.control.validation",
    "compute_metrics": "hcomc.metrics",
    "METRICS": "hcomc.metrics",
    "load_corridor": "hcomc.corridor",
    "simulate_corridor": "hcomc.metrics.corridor.run",
    "Impairments": "hcomc.robustness.impairments",
    "CHANNELS": "hcomc.robustness",
    "FAULTS": "hcomc.robustness",
    "ShieldParams": "hcomc.robustness",
    "ChannelParams": "hcomc.robustness",
    "FaultParams": "hcomc.robustness",
    "StepListener": "hcomc.interface.listener",
    "run": "hcomc.experiments.library",
    "compare": "hcomc.experiments.library",
    "ComparisonResult": "hcomc.experiments.library",
    "sections": "hcomc.corridor.road",
    "export_corridor": "hcomc.sumo.corridor",
    "MergeEnv": "hcomc.envs.merge_env",
    "MergeParallelEnv": "hcomc.envs.multi_agent",
    "CorridorMergeEnv": "hcomc.envs.corridor.env",
    "CorridorParallelEnv": "hcomc.envs.corridor.multi_agent",
    "ControllerPolicy": "hcomc.envs.policies",
    "evaluate_policies": "hcomc.envs.policies",
    "policy_summary": "hcomc.envs.policies",
    "compare_policies": "hcomc.envs.policies",
    "replay": "hcomc.viz.replay",
    "git_revision": "hcomc.sim.manifest",
    "export_commonroad": "hcomc.commonroad.export",
    "commonroad_contacts": "hcomc.commonroad.contacts",
}
"""Each name of the library face and the module that defines it (loaded on first use)."""

_EXTRAS: dict[str, str] = {
    "gymnasium": "envs",
    "pettingzoo": "envs",
    "libsumo": "sumo",
    "sumolib": "sumo",
    "commonroad": "commonroad",
    "commonroad_dc": "commonroad",
}
"""The packages of hcomc's optional extras: package -> the extra that installs it."""

__all__ = [
    "CHANNELS",
    "FAULTS",
    "METRICS",
    "ChannelParams",
    "ComparisonResult",
    "ConfigError",
    "ControllerFailed",
    "ControllerPolicy",
    "CorridorMergeEnv",
    "CorridorParallelEnv",
    "FaultParams",
    "Impairments",
    "InvalidPlan",
    "Lane",
    "MergeController",
    "MergeEnv",
    "MergeGroup",
    "MergeParallelEnv",
    "MergePlan",
    "Mode",
    "ScenarioConfig",
    "ShieldParams",
    "Simulation",
    "SimulationLog",
    "StepListener",
    "TrafficView",
    "__version__",
    "commonroad_contacts",
    "compare",
    "compare_policies",
    "compute_metrics",
    "evaluate_policies",
    "export_commonroad",
    "export_corridor",
    "git_revision",
    "load_config",
    "load_corridor",
    "make_controller",
    "policy_summary",
    "registered",
    "replay",
    "run",
    "run_ensemble",
    "sections",
    "simulate",
    "simulate_corridor",
]


def __getattr__(name: str) -> Any:
    """A name of the library face, loaded from its module on first use (PEP 562)."""
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'hcomc' has no attribute {name!r}")
    try:
        module = import_module(home)
    except ModuleNotFoundError as missing:
        extra = _EXTRAS.get((missing.name or "").partition(".")[0])
        if extra is None:
            raise
        raise ImportError(
            f"hcomc.{name} needs the optional extra '{extra}' ({missing.name} is not "
            f"installed): pip install 'hcomc[{extra}]'",
            name=missing.name,
        ) from missing
    value = getattr(module, name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_HOMES})
