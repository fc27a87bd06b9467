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
* corridors: :func:`load_corridor`, :func:`simulate_corridor`
* robustness: :class:`FaultedSimulation`, :data:`CHANNELS`, :data:`FAULTS`, :class:`ShieldParams`
"""

from importlib import import_module
from importlib.metadata import PackageNotFoundError, version
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from hcomc.config import ConfigError, ScenarioConfig, load_config
    from hcomc.control.registry import make_controller, registered
    from hcomc.control.validation import ControllerFailed, InvalidPlan
    from hcomc.corridor import load_corridor
    from hcomc.interface import MergeController, MergeGroup, MergePlan, Mode, TrafficView
    from hcomc.metrics import METRICS, compute_metrics
    from hcomc.road import Lane
    from hcomc.robustness import CHANNELS, FAULTS, ShieldParams
    from hcomc.robustness.engine import FaultedSimulation
    from hcomc.sim.corridor.run import simulate_corridor
    from hcomc.sim.engine import Simulation, simulate
    from hcomc.sim.ensemble import run_ensemble
    from hcomc.sim.log import SimulationLog

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
    "simulate_corridor": "hcomc.sim.corridor.run",
    "FaultedSimulation": "hcomc.robustness.engine",
    "CHANNELS": "hcomc.robustness",
    "FAULTS": "hcomc.robustness",
    "ShieldParams": "hcomc.robustness",
}
"""Each name of the library face and the module that defines it (loaded on first use)."""

__all__ = [
    "CHANNELS",
    "FAULTS",
    "METRICS",
    "ConfigError",
    "ControllerFailed",
    "FaultedSimulation",
    "InvalidPlan",
    "Lane",
    "MergeController",
    "MergeGroup",
    "MergePlan",
    "Mode",
    "ScenarioConfig",
    "ShieldParams",
    "Simulation",
    "SimulationLog",
    "TrafficView",
    "__version__",
    "compute_metrics",
    "load_config",
    "load_corridor",
    "make_controller",
    "registered",
    "run_ensemble",
    "simulate",
    "simulate_corridor",
]


def __getattr__(name: str) -> Any:
    """A name of the library face, loaded from its module on first use (PEP 562)."""
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'hcomc' has no attribute {name!r}")
    value = getattr(import_module(home), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_HOMES})
