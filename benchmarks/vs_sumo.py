"""Side-by-side throughput of hcomc and SUMO (libsumo, in process): vehicle-steps per second.

Two scenes at about N = 100, 500 and 2000 vehicles, 60 simulated seconds at dt = 0.1 s:

* ``line``: one lane, N IDM vehicles at their equilibrium spacing at 25 m/s, the first one
  cruising at 25 m/s. Our engine has no ring road, so both engines get the same long
  straight road with the same density instead (hcomc: the ``platoon`` scenario with a
  constant leader profile; SUMO: one 1-lane edge built with netconvert, every vehicle
  inserted at t = 0 at our positions and speeds).
* ``onramp``: Condition 1 with the mainline stretched as in ``throughput.py``, no merge
  controller; SUMO runs the same scene exported by :func:`hcomc.sumo.export.export_scenario`.

Only stepping is timed (scene loading and allocation excluded in both engines). Engines
alternate within one process, ``--repeats`` times, and the median is reported, so a loaded
machine affects both alike. Before each timed run, of either engine, the garbage of the
earlier ones is collected (``gc.collect()``): without it the first hcomc run after SUMO's
2,000-vehicle scene ran at about half the rate of the next ones (measured: 6.3 against
10.7-11.9 M vehicle-steps/s on the 100-vehicle line, and 12.1 M with the collection).
SUMO's vehicle-steps are the number of vehicles on the road after each step, summed. SUMO
runs each scene twice: with collision detection off (the headline ``sumo_steps_per_s`` and
``ratio``; with continuous lane changes SUMO's collision check grows about quadratically with
the vehicles on a lane and makes the on-ramp scene many times slower) and with the exported
options unchanged (``sumo_checked_steps_per_s``, ``ratio_checked``; collisions detected and
counted, as our engine does).

``--reproduce-seeds S`` also runs ``hcomc reproduce --seeds S --workers W``
(``--reproduce-workers``, default 1; ``reproduce``'s own default is every core) and compares
its wall time with the time SUMO needs for the same vehicle-steps (the sum of
``vehicle_steps`` in the run manifests) at the reproduced scene size (Condition 1 as
configured, 120 s including the warm-up, collision detection off; SUMO's rate is measured
before and after the reproduce run and the faster one counts). Its wall time includes
everything ``reproduce`` does (undisturbed reference runs, metrics, tables, report figures,
process start); ``hcomc_runs_wall_s`` is the part spent inside the runs, and
``hcomc_decisions_s`` the merge controllers' decisions alone (every plan of every run, seeded
and paper scenario: the tables' mean decision time times the plans), a floor under
``reproduce``'s time that no faster simulation can lower.

``--ensemble N`` (default 100) runs N Condition 1 runs as one ensemble
(:func:`hcomc.sim.ensemble.run_ensemble`, on every core) and compares their aggregate
vehicle-steps/s with SUMO's single-run rate on the same scene; the same ensemble on one thread
takes turns with it (the rate of one core).

    python benchmarks/vs_sumo.py [--json] [--sizes 100 500 2000] [--repeats 3]
                                 [--reproduce-seeds 1 [--reproduce-workers 1]]
                                 [--ensemble 100]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core per engine run (only the ensemble uses more)

import argparse  # noqa: E402
import gc  # noqa: E402
import json  # noqa: E402
import shutil  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from pathlib import Path  # noqa: E402

import pandas as pd  # noqa: E402
from throughput import machine, scene_config  # noqa: E402

from hcomc.config import ConfigError, ScenarioConfig, load_config  # noqa: E402
from hcomc.road import Kind  # noqa: E402
from hcomc.sim.demand import generate_demand  # noqa: E402
from hcomc.sim.engine import Simulation  # noqa: E402
from hcomc.sumo import SumoMissingError, import_libsumo, sumo_binary  # noqa: E402
from hcomc.sumo.export import export_scenario  # noqa: E402
from hcomc.sumo.routes import vtype_attributes  # noqa: E402

LINE_SPEED = 25.0  # [m/s] cruising speed of the one-lane scene
SEED = 0
# with continuous lane changes (lanechange.duration > 0) SUMO's collision check grows about
# quadratically with the vehicles on a lane and dominates its step time on the on-ramp scene
NO_COLLISION_CHECK = ["--collision.action", "none"]


@dataclass(frozen=True, slots=True)
class Timing:
    """One timed run of one engine."""

    vehicle_steps: int
    steps: int
    wall_s: float

    @property
    def rate(self) -> float:
        """Vehicle-steps per second."""
        return self.vehicle_steps / self.wall_s


@dataclass(frozen=True, slots=True)
class Scene:
    """A scene in both engines: our config and the SUMO command line that loads the same."""

    name: str
    size: int
    config: ScenarioConfig
    sumo_args: list[str]


# --------------------------------------------------------------------------- scenes
def line_config(n: int, duration: float) -> ScenarioConfig:
    """One lane, ``n`` vehicles at equilibrium spacing, the leader at constant speed."""
    platoon = {"followers": n - 1, "initial_speed": LINE_SPEED, "profile": [[0.0, LINE_SPEED]]}
    base = load_config("platoon", duration=duration, warmup=0.0, platoon=platoon)
    spacing = LINE_SPEED * 2.0 + base.road.vehicle_length  # above the equilibrium spacing
    length = max(10_000.0, 4.0 / 3.0 * spacing * n + 4 * LINE_SPEED * duration)
    road = {
        "length": length,
        "ramp_start": 0.1 * length,
        "accel_lane_start": 0.2 * length,
        "accel_lane_end": 0.2 * length + 250.0,
    }
    return load_config("platoon", duration=duration, warmup=0.0, platoon=platoon, road=road)


def _run(cmd: list[str]) -> None:
    done = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"{cmd[0]} failed: {(done.stderr or done.stdout).strip()[-300:]}")


def export_line(config: ScenarioConfig, out: Path) -> list[str]:
    """The one-lane scene as a SUMO network + routes with our vehicles; its SUMO options."""
    out.mkdir(parents=True, exist_ok=True)
    length = config.road.length
    (out / "line.nod.xml").write_text(
        f'<nodes><node id="a" x="0" y="0"/><node id="b" x="{length:.1f}" y="0"/></nodes>\n'
    )
    speed = max(config.hdv.desired_speed, config.cav.desired_speed) + 5.0
    (out / "line.edg.xml").write_text(
        f'<edges><edge id="e" from="a" to="b" numLanes="1" speed="{speed:.2f}"/></edges>\n'
    )
    net = out / "line.net.xml"
    _run(
        [
            sumo_binary("netconvert"),
            "--node-files",
            str(out / "line.nod.xml"),
            "--edge-files",
            str(out / "line.edg.xml"),
            "--output-file",
            str(net),
        ]
    )
    demand = generate_demand(config, None)  # type: ignore[arg-type]  # platoon: no randomness
    kind = Kind.HDV if config.platoon.kind == "hdv" else Kind.CAV
    follower = vtype_attributes(config, kind)
    leader = {**follower, "id": "leader", "maxSpeed": f"{LINE_SPEED:.6g}"}
    rows = ['<?xml version="1.0" encoding="UTF-8"?>', "<routes>"]
    for attrs in (leader, follower):
        rows.append("    <vType " + " ".join(f'{k}="{v}"' for k, v in attrs.items()) + "/>")
    rows.append('    <route id="r" edges="e"/>')
    for i in range(demand.n):
        vtype = "leader" if i == 0 else follower["id"]
        rows.append(
            f'    <vehicle id="v{i}" type="{vtype}" route="r" depart="0" departLane="0" '
            f'departPos="{demand.x[i]:.3f}" departSpeed="{demand.v[i]:.3f}"/>'
        )
    rows.append("</routes>")
    routes = out / "line.rou.xml"
    routes.write_text("\n".join(rows) + "\n")
    return [
        "-n",
        str(net),
        "-r",
        str(routes),
        "--step-length",
        f"{config.dt:.6g}",
        "--step-method.ballistic",
        "true",
        "--seed",
        str(SEED),
    ]


def make_scenes(sizes: list[int], duration: float, tmp: Path) -> list[Scene]:
    """Both scenes at every size, exported for SUMO into ``tmp``."""
    scenes = []
    for n in sizes:
        line = line_config(n, duration)
        scenes.append(Scene("line", n, line, export_line(line, tmp / f"line{n}")))
        ramp = scene_config(n, duration)
        exported = export_scenario(ramp, SEED, tmp / f"onramp{n}")
        scenes.append(Scene("onramp", n, ramp, ["-c", str(exported.sumocfg)]))
    return scenes


# --------------------------------------------------------------------------- engines
def time_hcomc(config: ScenarioConfig) -> Timing:
    """Time ``Simulation.run()`` (allocation excluded)."""
    sim = Simulation(config, SEED)
    gc.collect()  # the earlier runs' garbage (module docstring)
    start = time.perf_counter()
    sim.run()
    wall = time.perf_counter() - start
    return Timing(sim.vehicle_steps, sim.n_warmup + sim.n_steps, wall)


def time_sumo(args: list[str], steps: int) -> Timing:
    """Time ``steps`` libsumo steps of the loaded scene (loading excluded)."""
    libsumo = import_libsumo()
    libsumo.start(
        [
            sumo_binary("sumo"),
            *args,
            "--no-step-log",
            "true",
            "--no-warnings",
            "true",
            "--end",
            "1e9",
        ]
    )
    try:
        count = libsumo.vehicle.getIDCount
        step = libsumo.simulationStep
        vehicle_steps = 0
        gc.collect()
        start = time.perf_counter()
        for _ in range(steps):
            step()
            vehicle_steps += count()
        wall = time.perf_counter() - start
    finally:
        libsumo.close()
    return Timing(vehicle_steps, steps, wall)


def median_rate(timings: list[Timing]) -> float:
    """Median vehicle-steps/s over repetitions."""
    return statistics.median(t.rate for t in timings)


def compare(scenes: list[Scene], repeats: int) -> list[dict[str, object]]:
    """Both engines on every scene, alternating, ``repeats`` times; medians and their ratios.

    SUMO runs twice per repetition: with collision detection off (``sumo_steps_per_s``, the
    headline ``ratio``: SUMO's fastest setting, so the ratio is conservative) and with the
    exported options unchanged (``sumo_checked_*``: collisions detected and counted, as in
    our engine).
    """
    ours: dict[int, list[Timing]] = {k: [] for k in range(len(scenes))}
    fast: dict[int, list[Timing]] = {k: [] for k in range(len(scenes))}
    checked: dict[int, list[Timing]] = {k: [] for k in range(len(scenes))}
    for _ in range(repeats):
        for k, scene in enumerate(scenes):
            ours[k].append(time_hcomc(scene.config))
            steps = ours[k][-1].steps
            fast[k].append(time_sumo([*scene.sumo_args, *NO_COLLISION_CHECK], steps))
            checked[k].append(time_sumo(scene.sumo_args, steps))
    rows: list[dict[str, object]] = []
    for k, scene in enumerate(scenes):
        h, s, c = median_rate(ours[k]), median_rate(fast[k]), median_rate(checked[k])
        steps = ours[k][0].steps
        rows.append(
            {
                "scene": scene.name,
                "size": scene.size,
                "steps": steps,
                "hcomc_vehicles": round(ours[k][0].vehicle_steps / steps),
                "sumo_vehicles": round(fast[k][0].vehicle_steps / steps),
                "hcomc_steps_per_s": round(h),
                "sumo_steps_per_s": round(s),
                "ratio": round(h / s, 2),
                "sumo_checked_steps_per_s": round(c),
                "ratio_checked": round(h / c, 2),
                "repeats": repeats,
            }
        )
    return rows


# ---------------------------------------------------------------------------- ensemble
def ensemble(runs: int, repeats: int, tmp: Path) -> dict[str, object]:
    """``runs`` Condition 1 runs (seeds 0..runs-1) as one ensemble on every core, against
    SUMO's single-run rate on the same scene (seed ``SEED``, collision detection off); the
    median of ``repeats`` timed ensembles, as for the scenes. The same ensemble on one
    thread takes turns with it: the rate of one core, from which the rate of more cores
    is projected."""
    from hcomc.sim.ensemble import run_ensemble

    config = load_config("C1")
    run_ensemble([Simulation(config, runs)])  # load the compiled kernels
    walls: dict[int | None, list[float]] = {None: [], 1: []}
    for _ in range(repeats):
        for threads, timed in walls.items():
            sims = [Simulation(config, seed) for seed in range(runs)]
            gc.collect()
            start = time.perf_counter()
            run_ensemble(sims, threads=threads)
            timed.append(time.perf_counter() - start)
    wall, wall_one = statistics.median(walls[None]), statistics.median(walls[1])
    vehicle_steps = sum(sim.vehicle_steps for sim in sims)
    exported = export_scenario(config, SEED, tmp / "ensemble_c1")
    steps = round((config.warmup + config.duration) / config.dt)
    args = ["-c", str(exported.sumocfg), *NO_COLLISION_CHECK]
    rate = median_rate([time_sumo(args, steps) for _ in range(repeats)])
    return {
        "runs": runs,
        "threads": numba_threads(),
        "vehicle_steps": vehicle_steps,
        "hcomc_wall_s": round(wall, 3),
        "hcomc_steps_per_s": round(vehicle_steps / wall),
        "hcomc_one_thread_steps_per_s": round(vehicle_steps / wall_one),
        "sumo_steps_per_s": round(rate),
        "ratio": round(vehicle_steps / wall / rate, 2),
    }


def numba_threads() -> int:
    """Threads the ensemble runs on."""
    import numba

    return int(numba.get_num_threads())


# --------------------------------------------------------------------------- reproduce
def reproduce(seeds: int, workers: int, repeats: int, tmp: Path) -> dict[str, object]:
    """``hcomc reproduce --seeds S --workers W`` against SUMO at the same vehicle-steps."""
    out = tmp / "reproduce"
    hcomc = shutil.which("hcomc")
    cmd = [hcomc] if hcomc else [sys.executable, "-m", "hcomc"]
    config = load_config("C1")
    exported = export_scenario(config, SEED, tmp / "reproduce_c1")
    steps = round((config.warmup + config.duration) / config.dt)
    args = ["-c", str(exported.sumocfg), *NO_COLLISION_CHECK]
    # SUMO's rate is taken before and after the long reproduce run, and the faster of the two
    # counts: this machine's speed can change by 2x within minutes, and the faster SUMO is the
    # harder comparison for us
    before = [time_sumo(args, steps) for _ in range(repeats)]
    start = time.perf_counter()
    _run([*cmd, "reproduce", "--seeds", str(seeds), "--workers", str(workers), "--out", str(out)])
    wall = time.perf_counter() - start
    after = [time_sumo(args, steps) for _ in range(repeats)]
    manifests = sorted((out / "manifests").glob("*.json"))
    vehicle_steps = sum(json.loads(p.read_text())["vehicle_steps"] for p in manifests)
    runs = pd.read_csv(out / "runs.csv")
    every = pd.concat([runs, pd.read_csv(out / "paper_scenario.csv")])
    plans = every["replans"].fillna(0) + every["decision_ms"].notna()
    decided_s = plans * every["decision_ms"].fillna(0) / 1e3  # a run's plans x their mean
    by_configuration = decided_s.groupby(every["configuration"]).sum().sort_values()[::-1]
    rate = max(median_rate(before), median_rate(after))
    sumo_s = vehicle_steps / rate
    return {
        "seeds": seeds,
        "workers": workers,
        "runs": len(manifests),
        "vehicle_steps": vehicle_steps,
        "hcomc_wall_s": round(wall, 2),
        "hcomc_runs_wall_s": round(float(runs["wall_s"].sum()), 2),
        "hcomc_decisions": int(plans.sum()),
        "hcomc_decisions_s": round(float(decided_s.sum()), 2),
        "hcomc_decisions_s_by_configuration": {
            str(name): round(float(seconds), 2) for name, seconds in by_configuration.items()
        },
        "sumo_vehicles": round(before[0].vehicle_steps / steps),
        "sumo_steps_per_s_before": round(median_rate(before)),
        "sumo_steps_per_s_after": round(median_rate(after)),
        "sumo_steps_per_s": round(rate),
        "sumo_wall_s": round(sumo_s, 2),
        "ratio": round(sumo_s / wall, 3),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 500, 2000])
    parser.add_argument("--duration", type=float, default=60.0, help="simulated seconds per run")
    parser.add_argument("--repeats", type=int, default=3, help="alternating repetitions")
    parser.add_argument(
        "--reproduce-seeds",
        type=int,
        default=0,
        help="also compare 'hcomc reproduce --seeds S' (0: skip)",
    )
    parser.add_argument(
        "--reproduce-workers",
        type=int,
        default=1,
        help="worker processes of that 'hcomc reproduce' (its own default: every core)",
    )
    parser.add_argument(
        "--ensemble",
        type=int,
        default=100,
        help="also compare an ensemble of this many C1 runs (0: skip)",
    )
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    if min(args.sizes) < 2 or args.repeats < 1 or min(args.reproduce_seeds, args.ensemble) < 0:
        parser.error("--sizes must be >= 2, --repeats >= 1, --reproduce-seeds and --ensemble >= 0")
    if args.reproduce_workers < 1:
        parser.error("--reproduce-workers must be >= 1")
    try:
        with tempfile.TemporaryDirectory(prefix="hcomc-vs-sumo-") as name:
            tmp = Path(name)
            rows = compare(make_scenes(args.sizes, args.duration, tmp), args.repeats)
            seeds = args.reproduce_seeds
            workers = args.reproduce_workers
            repro = reproduce(seeds, workers, args.repeats, tmp) if seeds else None
            batch = ensemble(args.ensemble, args.repeats, tmp) if args.ensemble else None
    except (ConfigError, SumoMissingError, RuntimeError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
    report(rows, repro, batch, as_json=args.json)


def report(
    rows: list[dict[str, object]],
    repro: dict[str, object] | None,
    batch: dict[str, object] | None,
    *,
    as_json: bool,
) -> None:
    """Print the figures (a table, or one JSON object)."""
    facts = {**machine(), "sumo": sumo_version(), "load_average": os.getloadavg()}
    if as_json:
        print(json.dumps({"machine": facts, "results": rows, "reproduce": repro,
                          "ensemble": batch}))  # fmt: skip
        return
    print("machine:", ", ".join(f"{k} {v}" for k, v in facts.items()))
    head = ("scene", "size", "veh hcomc", "veh SUMO", "hcomc veh-steps/s", "SUMO veh-steps/s",
            "ratio", "SUMO checked", "ratio")  # fmt: skip
    keys = ("scene", "size", "hcomc_vehicles", "sumo_vehicles", "hcomc_steps_per_s",
            "sumo_steps_per_s", "ratio", "sumo_checked_steps_per_s", "ratio_checked")  # fmt: skip
    print(" ".join(f"{h:>{max(len(h), 7)}}" for h in head))
    for r in rows:
        print(" ".join(f"{r[k]:>{max(len(h), 7)}}" for h, k in zip(head, keys, strict=True)))
    if batch is not None:
        print(
            f"ensemble of {batch['runs']} C1 runs on {batch['threads']} threads: "
            f"{batch['hcomc_steps_per_s']:,} veh-steps/s aggregate; SUMO single run "
            f"{batch['sumo_steps_per_s']:,}; ratio {batch['ratio']}"
        )
    if repro is not None:
        print(
            f"reproduce --seeds {repro['seeds']} --workers {repro['workers']}: "
            f"{repro['runs']} runs, {repro['vehicle_steps']:,} vehicle-steps in "
            f"{repro['hcomc_wall_s']} s ({repro['hcomc_runs_wall_s']} s inside the runs, "
            f"{repro['hcomc_decisions']:,} decisions taking {repro['hcomc_decisions_s']} s); "
            f"SUMO at {repro['sumo_steps_per_s']:,} veh-steps/s needs {repro['sumo_wall_s']} s; "
            f"ratio SUMO time / hcomc time {repro['ratio']}"
        )


def sumo_version() -> str:
    """Version of the libsumo binding."""
    libsumo = import_libsumo()
    version: Callable[[], object] | None = getattr(libsumo, "getVersion", None)
    return str(version()[1]) if version is not None else "unknown"  # type: ignore[index]


if __name__ == "__main__":
    main()
