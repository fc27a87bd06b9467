# ruff: noqa: E402  (notebook cells import what they use)
"""The hcomc Python API in notebook-sized steps (each ``# %%`` block is one notebook cell).

Run it as a script (``python examples/notebook_api.py``) or open it in Jupyter/VS Code as a
notebook. docs/api.md explains every call. The test suite runs this file, so it stays correct.
"""

# %% 1. Load a preset with overrides
from hcomc import load_config

# flat keys resolve to their one home (cav_penetration -> demand.cav_penetration); dotted
# keys and nested tables work too; every value is validated like a config file's
config = load_config("C2", cav_penetration=0.5, duration=60.0)
same = load_config("C2", **{"demand.cav_penetration": 0.5, "duration": 60.0})
assert config == same
print(config.name, "|", config.description)
print("lane-2 headway from C2:", config.demand.mean_headway_main_2, "s")

# %% 2. Simulate and step
from hcomc import Simulation

sim = Simulation(config, seed=4)  # the merge controller is config.control.controller
for _ in range(50):  # step() advances every vehicle by dt without logging
    sim.step()
print(f"t = {sim.t:.1f} s, {int(sim.active.sum())} vehicles on the road")

log = Simulation(config, seed=4).run()  # warm-up, then `duration` seconds, logged
print(log)

# %% 3. The paper's metrics of the merge, from the log
from hcomc import compute_metrics

# The engine records the six key vehicles (Section II-A) of every ramp vehicle when it
# enters the control zone, with or without a merge controller; the metrics compare them
# with the undisturbed run (same scenario and seed, the ramp vehicle never released).
first = log.meta["key_groups"][0]
group = {role: vehicle for role, vehicle in first.items() if role != "t"}  # role -> slot
print("key vehicles:", group)
reference = Simulation(config, seed=4, counterfactual=True).run()
metrics = compute_metrics(log, reference=reference)
print({k: round(v, 3) if isinstance(v, float) else v for k, v in metrics.items()})

# %% 4. Tables for pandas
frame = log.to_frame()  # one row per (logged time, vehicle on the road)
events = log.events_frame()  # insertions, lane changes, merges, collisions, ...
print(frame.groupby("lane")["v"].mean().astype(float).round(2))
print(events["kind"].value_counts())

# %% 5. The same scenario with HCOMC
hcomc_config = load_config("C2", cav_penetration=0.5, duration=60.0, controller="hcomc")
hcomc_sim = Simulation(hcomc_config, seed=4)
hcomc_log = hcomc_sim.run()
plan = hcomc_sim.decisions[0]
print(f"HCOMC: mode {plan.mode.name}, merge at {plan.merge_x:.1f} m, {plan.decision_ms:.0f} ms")

# %% 6. A custom merge controller
import numpy as np

from hcomc import MergeGroup, MergePlan, Mode, TrafficView


class GapAcceptance:
    """Never cooperates: VR merges by gap acceptance, VMC drives on (a do-nothing baseline)."""

    name = "gap-acceptance"

    def __init__(self) -> None:
        self.seen: list[float] = []

    def plan(self, view: TrafficView, group: MergeGroup, rng: np.random.Generator) -> MergePlan:
        gap = view.x[group.vmf] - view.x[group.vmc] if min(group.vmf, group.vmc) >= 0 else np.inf
        self.seen.append(float(gap))
        return MergePlan(group, Mode.NONE, view.t, reason=f"lane-1 gap {gap:.1f} m; no help")


controller = GapAcceptance()
custom = Simulation(config, seed=4, controller=controller)
custom_log = custom.run()
print("custom plans:", [p["reason"] for p in custom_log.meta["plans"]])
assert len(controller.seen) == len(custom.decisions) >= 1

# %% 7. Runs and comparisons: hcomc run and hcomc compare from Python
import hcomc

# one scenario, one controller, over seeds: the rows of `hcomc run C2 --controller hcomc`
runs = hcomc.run("C2", "hcomc", seeds=2, overrides={"cav_penetration": 0.5, "duration": 60.0})
print(runs[["seed", "merged", "mode", "critical_distance", "fuel"]])

# cells of the benchmark suite x controllers x seeds, paired by seed: `hcomc compare`
result = hcomc.compare(["fifo", "hcomc"], conditions=["C1"], seeds=2, overrides={"duration": 40.0})
print(result)
print(result.success[["condition", "configuration", "merged", "runs"]])
print(result.effects[["condition", "metric", "a", "b", "median_diff", "a_lower", "n"]])
