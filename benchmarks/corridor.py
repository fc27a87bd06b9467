"""Corridor throughput: hcomc's corridor simulator against SUMO (libsumo, in process).

The scene is a corridor preset (``--corridor``, default ``corridor``: 10 km, 3 lanes, 5
on-ramps, 4 off-ramps, one hour of demand with a peak), loaded with
:func:`hcomc.corridor.load_corridor` and simulated for ``--duration`` seconds (default: the
corridor's own duration) from its start, at its step length (0.1 s), with no ramp control:

* hcomc: :func:`hcomc.metrics.corridor.simulate_corridor` (seed: the corridor's), the call timed
  as a whole. Its first call compiles the kernels, or loads them from numba's cache: one
  untimed 10-second call comes first, and its wall time is reported as ``first_call_s``.
  ``compile_s`` is that first call's wall time in a fresh child process with an empty cache
  (``NUMBA_CACHE_DIR`` a new temporary directory): the compilation from scratch, as after a
  change of the kernels' sources (``--no-cold-compile`` skips it).
* SUMO: the same corridor exported by :func:`hcomc.sumo.corridor.export_corridor` into a
  temporary directory (network, routes, induction loops, ``corridor.sumocfg``), started with
  that configuration plus ``--no-step-log``, ``--duration-log.disable`` (and vs_sumo.py's
  ``--no-warnings``); only the stepping is timed (loading excluded), as in vs_sumo.py, whose
  SUMO timing this script reuses. As there, SUMO runs twice: with collision detection off
  (the headline ``sumo_steps_per_s`` and ``ratio``) and with the exported options unchanged
  (``sumo_checked_steps_per_s``, ``ratio_checked``: collisions detected and counted). SUMO
  also writes its induction loops' output, as the exported scenario asks. Its statistics of
  each run (vehicles loaded, inserted, waiting to be inserted at the end, teleports,
  collisions) are reported.

Vehicle-steps are the vehicles on the road after each step, summed (hcomc:
``run.vehicle_steps``; SUMO: ``libsumo.vehicle.getIDCount()`` after every step); the rates
are vehicle-steps per wall second, and ``real_time_factor`` is simulated seconds per wall
second. The engines alternate within one process, ``--repeats`` times, the garbage of the
earlier runs collected before each timed run (``gc.collect()``), and the medians count.

**Memory.** Each engine also runs the whole ``--duration`` once more in a fresh child process
(``--no-memory`` skips this). ``*_peak_rss_mb`` is the child's peak resident memory at the
end of the run minus its resident memory before the run (MB = 2^20 bytes). Both are taken
after the imports (hcomc: and the 10-second warm-up call; SUMO: before ``libsumo.start``, so
that both include building the scene), once the C heap's free memory has been returned to
the system (glibc's ``malloc_trim``: the run must not grow unseen into pages the imports
freed) and the peak lowered to the current resident memory (``/proc/self/clear_refs``,
Linux: the transient peaks of the imports and of compiling the kernels must not hide the
run's). The peak is Linux's ``VmHWM`` (the figure ``resource.getrusage(RUSAGE_SELF).ru_maxrss``
reports, but without the peaks of exited threads, which cannot be lowered); elsewhere
``ru_maxrss``, not lowered (``peak_reset`` false: the growth is then a lower bound). The
children's absolute peaks are reported too. SUMO's child runs with collision detection off
and also records, untimed, the most vehicles waiting to be inserted at once and the
teleports.

``--trajectory-interval S`` passes ``trajectory_interval=S`` to every hcomc call, timed ones
included (0, the default: no trajectory log); the size of the memory run's
``run.trajectories`` (``DataFrame.memory_usage(deep=True).sum()``) is then reported as
``trajectories_bytes``.

**Controlled.** With ``--controllers hcomc …`` (default: ``hcomc``; none given: skipped)
hcomc also runs the corridor once per controller with that merge controller at every
on-ramp (the corridor's ``[control]`` table, controller replaced), after an untimed
10-second call that loads the controller's kernels; reported per controller under
``controlled``: the wall time of the whole call and ``real_time_factor`` (simulated seconds
per wall second, one process, one thread), the decisions and their wall time, collisions,
and per on-ramp the merged share and the 5th percentile of the events' least TTC.

    python benchmarks/corridor.py [--json] [--corridor corridor] [--duration 3600]
                                  [--repeats 3] [--trajectory-interval 0]
                                  [--engines hcomc sumo] [--no-memory]
                                  [--no-cold-compile] [--controllers hcomc fifo game]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core per engine run, as in vs_sumo.py

import argparse  # noqa: E402
import contextlib  # noqa: E402
import ctypes  # noqa: E402
import gc  # noqa: E402
import json  # noqa: E402
import resource  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
import xml.etree.ElementTree as ET  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

from throughput import machine  # noqa: E402
from vs_sumo import NO_COLLISION_CHECK, Timing, median_rate, sumo_version, time_sumo  # noqa: E402

from hcomc.config import ConfigError  # noqa: E402
from hcomc.corridor import Corridor, load_corridor  # noqa: E402
from hcomc.sim.manifest import git_revision  # noqa: E402
from hcomc.sumo import SumoMissingError, import_libsumo, sumo_binary  # noqa: E402
from hcomc.sumo.corridor import export_corridor  # noqa: E402

WARMUP_S = 10.0  # [s] simulated by the untimed first hcomc call that compiles the kernels
SUMO_REPORT = ["--duration-log.disable", "true"]  # time_sumo adds --no-step-log, --no-warnings
MB = 2**20
ENGINES = ("hcomc", "sumo")


def _simulate_corridor() -> Any:
    """:func:`hcomc.metrics.corridor.simulate_corridor`, imported only when hcomc runs."""
    try:
        from hcomc.metrics.corridor import simulate_corridor
    except ImportError as exc:
        raise RuntimeError(f"hcomc's corridor simulator cannot be imported ({exc})") from None
    return simulate_corridor


def _hcomc_options(trajectory_interval: float) -> dict[str, float]:
    return {"trajectory_interval": trajectory_interval} if trajectory_interval > 0 else {}


def _steps(c: Corridor, duration: float) -> int:
    return round(duration / c.corridor.step_length)


def _peak_bytes() -> int:
    """Peak resident memory of this process so far: ``VmHWM`` of ``/proc/self/status``
    (Linux), else ``ru_maxrss`` (KiB on Linux, bytes on macOS; here taken as KiB)."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def _trim_heap() -> None:
    """Return the C heap's free memory to the system (glibc's ``malloc_trim``; elsewhere
    nothing), so that a run's allocations show as growth instead of filling pages that the
    imports freed but kept resident."""
    with contextlib.suppress(AttributeError, OSError):
        ctypes.CDLL(None).malloc_trim(0)


def _reset_peak() -> bool:
    """Lower this process's peak resident memory to its current one (Linux >= 4.0: writing 5
    to ``/proc/self/clear_refs`` resets ``VmHWM``), so that a later peak is the run's own, not
    that of the imports or of compiling the kernels; False where that is not possible.

    ``ru_maxrss`` is not used after the reset: it is also the maximum of the process's exited
    threads' peaks, which the reset leaves as they were (in a child that had imported this
    script, a thread that exited during the imports held it at their peak, and the SUMO run
    then showed no growth at all).
    """
    try:
        with open("/proc/self/clear_refs", "w", encoding="ascii") as fh:
            fh.write("5")
        with open("/proc/self/status", encoding="ascii") as fh:
            return any(line.startswith("VmHWM:") for line in fh)
    except OSError:
        return False


# --------------------------------------------------------------------------- engines
def warm_up(c: Corridor, trajectory_interval: float) -> float:
    """One short hcomc run that compiles (or loads) the kernels; its wall time."""
    simulate = _simulate_corridor()
    start = time.perf_counter()
    simulate(c, seed=c.corridor.seed, duration=WARMUP_S, **_hcomc_options(trajectory_interval))
    return time.perf_counter() - start


def time_hcomc(c: Corridor, duration: float, trajectory_interval: float) -> Timing:
    """Time one ``simulate_corridor`` call (the whole call: building the scene included)."""
    simulate = _simulate_corridor()
    options = _hcomc_options(trajectory_interval)
    gc.collect()  # the earlier runs' garbage (vs_sumo.py's docstring)
    start = time.perf_counter()
    run = simulate(c, seed=c.corridor.seed, duration=duration, **options)
    wall = time.perf_counter() - start
    return Timing(int(run.vehicle_steps), _steps(c, duration), wall)


def time_controlled(c: Corridor, duration: float, controller: str) -> dict[str, Any]:
    """One timed run of ``c`` with ``controller`` at every on-ramp (module docstring)."""
    control = c.control.model_copy(update={"controller": controller})
    controlled = c.model_copy(update={"control": control})
    simulate = _simulate_corridor()
    simulate(controlled, seed=c.corridor.seed, duration=WARMUP_S)  # the controller's kernels
    gc.collect()
    start = time.perf_counter()
    run = simulate(controlled, seed=c.corridor.seed, duration=duration)
    wall = time.perf_counter() - start
    summary = run.summary()
    ramps = {
        ramp: {k: row["merge_events"][k] for k in ("events", "merged_share", "min_ttc_p05",
                                                    "fallbacks")}
        for ramp, row in summary["on_ramps"].items()
    }  # fmt: skip
    return {
        "controller": controller, "wall_s": round(wall, 2),
        "real_time_factor": round(duration / wall, 2), "decisions": run.decisions,
        "decision_s": round(run.decision_seconds, 2),
        "mean_decision_ms": round(1000 * run.decision_seconds / max(run.decisions, 1), 2),
        "collisions": run.collision_count, "arrived": summary["arrived"], "on_ramps": ramps,
    }  # fmt: skip


def sumo_statistics(directory: Path) -> dict[str, int]:
    """SUMO's ``statistics.xml`` of the last run closed in ``directory``."""
    root = ET.parse(directory / "statistics.xml").getroot()
    vehicles, teleports = root.find("vehicles"), root.find("teleports")
    safety = root.find("safety")
    if vehicles is None or teleports is None or safety is None:
        raise RuntimeError(f"unexpected SUMO statistics in {directory / 'statistics.xml'}")
    return {
        "loaded": int(vehicles.get("loaded", 0)),
        "inserted": int(vehicles.get("inserted", 0)),
        "running": int(vehicles.get("running", 0)),
        "waiting": int(vehicles.get("waiting", 0)),
        "teleports": int(teleports.get("total", 0)),
        "collisions": int(safety.get("collisions", 0)),
        "emergency_stops": int(safety.get("emergencyStops", 0)),
    }


def compare(
    c: Corridor,
    sumocfg: Path | None,
    duration: float,
    repeats: int,
    trajectory_interval: float,
    *,
    hcomc: bool,
) -> dict[str, Any]:
    """The engines on the corridor, alternating, ``repeats`` times; medians and ratios
    (``sumocfg`` None: SUMO not run; ``hcomc`` False: hcomc not run)."""
    steps = _steps(c, duration)
    ours: list[Timing] = []
    fast: list[Timing] = []
    checked: list[Timing] = []
    stats: dict[str, dict[str, int]] = {}
    first_call_s = warm_up(c, trajectory_interval) if hcomc else None
    for _ in range(repeats):
        if hcomc:
            ours.append(time_hcomc(c, duration, trajectory_interval))
        # the controlled corridor (HCOMC at every ramp) will be timed here, as a third engine
        if sumocfg is not None:
            args = ["-c", str(sumocfg), *SUMO_REPORT]
            fast.append(time_sumo([*args, *NO_COLLISION_CHECK], steps))
            stats["sumo"] = sumo_statistics(sumocfg.parent)
            checked.append(time_sumo(args, steps))
            stats["sumo_checked"] = sumo_statistics(sumocfg.parent)
    return summarise(c, duration, repeats, ours, fast, checked, stats, first_call_s)


def summarise(
    c: Corridor,
    duration: float,
    repeats: int,
    ours: list[Timing],
    fast: list[Timing],
    checked: list[Timing],
    stats: dict[str, dict[str, int]],
    first_call_s: float | None,
) -> dict[str, Any]:
    """The figures of :func:`compare` as one flat record (None where an engine did not run)."""
    steps = _steps(c, duration)
    h = median_rate(ours) if ours else None
    s = median_rate(fast) if fast else None
    k = median_rate(checked) if checked else None
    h_wall = statistics.median(t.wall_s for t in ours) if ours else None
    s_wall = statistics.median(t.wall_s for t in fast) if fast else None
    return {
        "scene": c.corridor.name,
        "duration": duration,
        "steps": steps,
        "repeats": repeats,
        "hcomc_vehicles": round(ours[0].vehicle_steps / steps) if ours else None,
        "sumo_vehicles": round(fast[0].vehicle_steps / steps) if fast else None,
        "hcomc_vehicle_steps": ours[0].vehicle_steps if ours else None,
        "sumo_vehicle_steps": fast[0].vehicle_steps if fast else None,
        "hcomc_wall_s": None if h_wall is None else round(h_wall, 3),
        "sumo_wall_s": None if s_wall is None else round(s_wall, 3),
        "hcomc_steps_per_s": None if h is None else round(h),
        "sumo_steps_per_s": None if s is None else round(s),
        "ratio": None if h is None or s is None else round(h / s, 2),
        "sumo_checked_steps_per_s": None if k is None else round(k),
        "ratio_checked": None if h is None or k is None else round(h / k, 2),
        "real_time_factor": None if h_wall is None else round(duration / h_wall, 1),
        "sumo_real_time_factor": None if s_wall is None else round(duration / s_wall, 1),
        "compile_s": None,
        "first_call_s": None if first_call_s is None else round(first_call_s, 2),
        "sumo_statistics": stats.get("sumo"),
        "sumo_checked_statistics": stats.get("sumo_checked"),
    }


# --------------------------------------------------------------------------- memory
def hcomc_child(source: str, duration: float, trajectory_interval: float) -> dict[str, Any]:
    """A full hcomc run in this (fresh) process: its peak resident memory."""
    c = load_corridor(source)
    warm_up(c, trajectory_interval)
    gc.collect()
    _trim_heap()
    reset = _reset_peak()
    base = _peak_bytes()
    simulate = _simulate_corridor()
    options = _hcomc_options(trajectory_interval)
    start = time.perf_counter()
    run = simulate(c, seed=c.corridor.seed, duration=duration, **options)
    wall = time.perf_counter() - start
    peak = _peak_bytes()
    frame = getattr(run, "trajectories", None)
    size = None if frame is None else int(frame.memory_usage(deep=True).sum())
    return {
        "peak_reset": reset,
        "rss_before_bytes": base,
        "peak_rss_bytes": peak,
        "rss_growth_bytes": peak - base,
        "trajectories_bytes": size,
        "trajectory_rows": None if frame is None else len(frame),
        "vehicle_steps": int(run.vehicle_steps),
        "wall_s": round(wall, 3),
    }


def sumo_child(sumocfg: str, steps: int) -> dict[str, Any]:
    """A full libsumo run (collision detection off) in this (fresh) process: its peak resident
    memory, the most vehicles waiting to be inserted at once and the teleports."""
    libsumo = import_libsumo()
    gc.collect()
    _trim_heap()
    reset = _reset_peak()
    base = _peak_bytes()
    cmd = [sumo_binary("sumo"), "-c", sumocfg, *SUMO_REPORT, *NO_COLLISION_CHECK]
    libsumo.start([*cmd, "--no-step-log", "true", "--no-warnings", "true", "--end", "1e9"])
    loaded = _peak_bytes()
    vehicle_steps = waiting = teleports = 0
    start = time.perf_counter()
    try:
        for _ in range(steps):
            libsumo.simulationStep()
            vehicle_steps += libsumo.vehicle.getIDCount()
            waiting = max(waiting, len(libsumo.simulation.getPendingVehicles()))
            teleports += libsumo.simulation.getStartingTeleportNumber()
    finally:
        wall = time.perf_counter() - start
        peak = _peak_bytes()
        libsumo.close()
    return {
        "peak_reset": reset,
        "rss_before_bytes": base,
        "rss_after_load_bytes": loaded,
        "peak_rss_bytes": peak,
        "rss_growth_bytes": peak - base,
        "most_waiting": waiting,
        "teleports": teleports,
        "vehicle_steps": vehicle_steps,
        "wall_s": round(wall, 3),
    }


def compile_child(source: str, trajectory_interval: float) -> dict[str, Any]:
    """The first hcomc call in this (fresh) process: compilation, or loading from the cache."""
    return {"first_call_s": warm_up(load_corridor(source), trajectory_interval)}


def cold_compile(source: str, trajectory_interval: float) -> float:
    """Wall time of hcomc's first call in a child process with an empty numba cache."""
    with tempfile.TemporaryDirectory(prefix="hcomc-numba-cache-") as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        result = _child("compile", source, trajectory_interval, env=env)
    return float(result["first_call_s"])


def _child(*args: object, env: dict[str, str] | None = None) -> dict[str, Any]:
    """This script's ``--child`` mode in a fresh interpreter (memory is the child's own)."""
    cmd = [sys.executable, __file__, "--child", *map(str, args)]
    done = subprocess.run(cmd, capture_output=True, text=True, check=False, env=env)
    if done.returncode != 0:
        raise RuntimeError(f"child {args[0]} failed: {done.stderr.strip()[-500:]}")
    result: dict[str, Any] = json.loads(done.stdout.strip().splitlines()[-1])
    return result


def memory(
    source: str,
    sumocfg: Path | None,
    duration: float,
    trajectory_interval: float,
    *,
    hcomc: bool,
) -> dict[str, Any]:
    """Peak resident memory of a ``duration`` run of each engine, each in a child process."""
    out: dict[str, Any] = {}
    if hcomc:
        h = _child("hcomc", source, duration, trajectory_interval)
        out["hcomc_peak_rss_mb"] = round(h["rss_growth_bytes"] / MB, 1)
        out["hcomc_child_peak_rss_mb"] = round(h["peak_rss_bytes"] / MB, 1)
        out["trajectories_bytes"] = h["trajectories_bytes"]
        out["hcomc_memory_run"] = h
    if sumocfg is not None:
        s = _child("sumo", sumocfg, _steps(load_corridor(source), duration))
        out["sumo_peak_rss_mb"] = round(s["rss_growth_bytes"] / MB, 1)
        out["sumo_child_peak_rss_mb"] = round(s["peak_rss_bytes"] / MB, 1)
        out["sumo_most_waiting"] = s["most_waiting"]
        out["sumo_memory_run"] = s
    return out


# --------------------------------------------------------------------------- main
def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--corridor", default="corridor", help="corridor preset or TOML file")
    parser.add_argument(
        "--duration", type=float, default=None, help="simulated seconds (default: the corridor's)"
    )
    parser.add_argument("--repeats", type=int, default=3, help="alternating repetitions")
    parser.add_argument(
        "--trajectory-interval",
        type=float,
        default=0.0,
        help="hcomc's trajectory_interval [s] (0: no trajectory log)",
    )
    parser.add_argument(
        "--engines", nargs="+", choices=ENGINES, default=list(ENGINES), help="engines to run"
    )
    parser.add_argument("--no-memory", action="store_true", help="skip the memory runs")
    parser.add_argument(
        "--no-cold-compile", action="store_true", help="skip the compilation with an empty cache"
    )
    parser.add_argument(
        "--controllers", nargs="*", default=["hcomc"],
        help="also time hcomc with each of these merge controllers at every on-ramp",
    )  # fmt: skip
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--child", nargs="+", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        kind, *rest = args.child
        if kind == "hcomc":
            result = hcomc_child(rest[0], float(rest[1]), float(rest[2]))
        elif kind == "compile":
            result = compile_child(rest[0], float(rest[1]))
        else:
            result = sumo_child(rest[0], int(rest[1]))
        print(json.dumps(result))
        return
    if args.repeats < 1 or args.trajectory_interval < 0:
        parser.error("--repeats must be >= 1, --trajectory-interval >= 0")
    hcomc = "hcomc" in args.engines
    try:
        c = load_corridor(args.corridor)
        duration = c.corridor.duration if args.duration is None else args.duration
        if not 0 < duration <= c.corridor.duration:
            parser.error(f"--duration must be in (0, {c.corridor.duration:g}]")
        with tempfile.TemporaryDirectory(prefix="hcomc-corridor-") as name:
            sumocfg = None
            if "sumo" in args.engines:
                sumocfg = export_corridor(c, Path(name) / c.corridor.name).sumocfg
            every = args.trajectory_interval
            row = compare(c, sumocfg, duration, args.repeats, every, hcomc=hcomc)
            row["trajectory_interval"] = every
            if hcomc and not args.no_cold_compile:
                row["compile_s"] = round(cold_compile(args.corridor, every), 2)
            if not args.no_memory:
                row.update(memory(args.corridor, sumocfg, duration, every, hcomc=hcomc))
            row["controlled"] = [time_controlled(c, duration, k) for k in args.controllers]
    except (ConfigError, SumoMissingError, RuntimeError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
    report(c, row, as_json=args.json)


def report(c: Corridor, row: dict[str, Any], *, as_json: bool) -> None:
    """Print the figures (a table, or one JSON object)."""
    facts = {**machine(), "revision": git_revision(), "load_average": os.getloadavg()}
    if row["sumo_steps_per_s"] is not None:
        facts["sumo"] = sumo_version()
    if as_json:
        print(json.dumps({"machine": facts, **row}))
        return
    print("machine:", ", ".join(f"{k} {v}" for k, v in facts.items()))
    print(
        f"corridor '{row['scene']}' ({c.corridor.description}): {row['duration']:g} s simulated "
        f"({row['steps']} steps of {c.corridor.step_length:g} s), median of {row['repeats']}"
    )
    head = ("engine", "vehicles", "veh-steps/s", "wall s", "real-time x", "peak RSS MB")
    lines = [
        ("hcomc", "hcomc_vehicles", "hcomc_steps_per_s", "hcomc_wall_s", "real_time_factor",
         "hcomc_peak_rss_mb"),
        ("SUMO, no collision check", "sumo_vehicles", "sumo_steps_per_s", "sumo_wall_s",
         "sumo_real_time_factor", "sumo_peak_rss_mb"),
        ("SUMO, collisions checked", "sumo_vehicles", "sumo_checked_steps_per_s", None, None,
         None),
    ]  # fmt: skip
    print(f"{head[0]:<26}" + "".join(f"{h:>13}" for h in head[1:]))
    for label, *keys in lines:
        if row.get(keys[1]) is None:  # the engine did not run
            continue
        cells = [_cell(row.get(k)) if k else "" for k in keys]
        print(f"{label:<26}" + "".join(f"{x:>13}" for x in cells))
    if row["ratio"] is not None:
        print(f"ratio hcomc / SUMO: {row['ratio']} (collisions checked: "
              f"{row['ratio_checked']}); target >= 10")  # fmt: skip
    if row["first_call_s"] is not None:
        print(f"hcomc's first call ({WARMUP_S:g} s simulated): {row['first_call_s']} s with "
              f"numba's cache as found, {_cell(row['compile_s'])} s with an empty cache "
              f"(compilation)")  # fmt: skip
    if row.get("trajectories_bytes") is not None:
        rows = row["hcomc_memory_run"]["trajectory_rows"]
        print(f"trajectories of the memory run (interval {row['trajectory_interval']:g} s): "
              f"{rows:,} rows, {row['trajectories_bytes']:,} bytes")  # fmt: skip
    for key, label in (("sumo_statistics", "SUMO"), ("sumo_checked_statistics", "SUMO checked")):
        if row.get(key):
            print(f"{label} at the end: " + ", ".join(f"{k} {v}" for k, v in row[key].items()))
    for run in row["controlled"]:
        print(
            f"hcomc with {run['controller']} at every on-ramp: {run['wall_s']} s, "
            f"{run['real_time_factor']}x real time (target >= 10), {run['decisions']:,} "
            f"decisions ({run['mean_decision_ms']} ms each), {run['collisions']} collisions"
        )
        for ramp, ev in run["on_ramps"].items():
            print(f"  {ramp}: " + ", ".join(f"{k} {_cell(v)}" for k, v in ev.items()))
    if "sumo_most_waiting" in row:
        run = row["sumo_memory_run"]
        print(f"SUMO memory run: at most {row['sumo_most_waiting']} vehicles waiting to be "
              f"inserted at once, {run['teleports']} teleports")  # fmt: skip


def _cell(value: object) -> str:
    if value is None:
        return "-"
    return f"{value:,}" if isinstance(value, int) else str(value)


if __name__ == "__main__":
    main()
