"""The speed work's targets in one run, each figure measured beside the reference it is held to.

One process measures, in this order:

* **single runs**: the ``line`` and ``onramp`` scenes of ``vs_sumo.py`` at 100 and 2,000
  vehicles, 60 simulated seconds; hcomc, SUMO (libsumo, collision detection off, its fastest
  setting) and the plain compiled IDM of ``step_cost.py`` at the same number of vehicles take
  turns scene by scene, ``--repeats`` times, and the medians give hcomc / SUMO (targets: at
  least 10x at about 100 vehicles and 20x at 2,000, both scenes) and, on the line, the plain
  IDM's vehicle-steps/s over hcomc's (target: at most 3);
* **the ensemble**: ``--ensemble`` Condition 1 runs advanced as one batch on every core,
  against SUMO's single-run rate on the same scene (target: 50x);
* **one HCOMC decision** on the 60 recorded problems of ``record_decisions.py``, each decided
  by the default controller with the generators of the recorded baseline (seeds 0, 1, 2), on
  every core (the rows of a population scored side by side) and on one, taking turns
  ``--repeats`` times, the median of the passes' medians (target: 5 ms) and its quality:
  every problem's mean hypervolume against the baseline's (equal quality: at least 0.99 of it
  on every problem);
* **the default reproduction**: ``hcomc reproduce --seeds S --workers W`` against SUMO's time
  for the same vehicle-steps (target: at most 0.25 of it), as ``vs_sumo.py`` measures it;

then, for every target not met, **the cost model**: the phases of the compiled step
(``step_cost.py``: ns per vehicle-step, the largest first) of the scenes behind it, the
decisions' time in NSGA-II's compiled search (the rollouts of its rows, its steps), the
lane-change game and the rest (``decision_latency.py --split``), the reproduction's time
in merge decisions; and, for the targets of many runs (the ensemble, the reproduction), the
cores that would meet them at this run's pace per core.

    python benchmarks/speed_targets.py [--repeats 3] [--ensemble 100] [--reproduce-seeds 30]
                                       [--reproduce-workers 2] [--no-decisions] [--json]

Every figure carries the run's stamp (date, host, hcomc version and revision).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core per engine run (only the ensemble uses more)
os.environ.setdefault("NUMBA_NUM_THREADS", str(os.cpu_count() or 1))  # ensemble, decisions

import argparse  # noqa: E402
import datetime  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
from dataclasses import asdict, dataclass  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numba  # noqa: E402
from decision_latency import split  # noqa: E402
from record_decisions import PROBLEMS_FILE, against_baseline, evaluate, load_decisions  # noqa: E402
from step_cost import measure, paper_following_rate, plain_idm_rate  # noqa: E402
from throughput import machine  # noqa: E402
from vs_sumo import (  # noqa: E402
    NO_COLLISION_CHECK,
    ensemble,
    line_config,
    make_scenes,
    reproduce,
    sumo_version,
    time_hcomc,
    time_sumo,
)

from hcomc.config import ConfigError  # noqa: E402
from hcomc.sim.manifest import git_revision  # noqa: E402
from hcomc.sumo import SumoMissingError  # noqa: E402

SIZES = {100: 10.0, 2000: 20.0}  # vehicles -> the least ratio to SUMO a single run must reach
DURATION = 60.0  # simulated seconds of a single-run scene
PLAIN_IDM_FACTOR = 3.0  # the line's step within this factor of the plain IDM's rate
ENSEMBLE_RATIO = 50.0  # ensemble vehicle-steps/s over SUMO's single-run rate
DECISION_MS = 5.0  # median of one HCOMC decision
EQUAL_QUALITY = 0.99  # least hypervolume ratio to the recorded baseline, on every problem
REPRODUCE_RATIO = 0.25  # hcomc reproduce's time over SUMO's for the same vehicle-steps


@dataclass(frozen=True, slots=True)
class Target:
    """One target of the speed work: what is measured, the bound, the figure and whether it
    is met; ``where`` says what the time is spent on when it is not."""

    name: str
    bound: str
    measured: str
    met: bool
    where: str = ""


def progress(message: str) -> None:
    """A line on stderr: the run takes minutes."""
    print(f"[{datetime.datetime.now():%H:%M:%S}] {message}", file=sys.stderr, flush=True)


def single_runs(repeats: int, tmp: Path) -> list[dict[str, Any]]:
    """hcomc, SUMO and the plain IDM on every scene, taking turns, ``repeats`` times; the
    median rates [vehicle-steps/s] and their ratios."""
    scenes = make_scenes(list(SIZES), DURATION, tmp)
    progress("single runs: loading the compiled step")
    for scene in scenes:  # untimed: the first run of a process loads the kernels
        time_hcomc(scene.config)
    rates: list[tuple[list[float], list[float], list[float]]] = [([], [], []) for _ in scenes]
    vehicles = [0] * len(scenes)
    for rep in range(repeats):
        for k, scene in enumerate(scenes):
            progress(f"single runs {rep + 1}/{repeats}: {scene.name}, {scene.size} vehicles")
            ours = time_hcomc(scene.config)
            theirs = time_sumo([*scene.sumo_args, *NO_COLLISION_CHECK], ours.steps)
            vehicles[k] = round(ours.vehicle_steps / ours.steps)
            rates[k][0].append(ours.rate)
            rates[k][1].append(theirs.rate)
            rates[k][2].append(plain_idm_rate(vehicles[k], ours.steps, 1))
    rows = []
    for k, scene in enumerate(scenes):
        hcomc, sumo, plain = (statistics.median(r) for r in rates[k])
        rows.append({"scene": scene.name, "size": scene.size, "vehicles": vehicles[k],
                     "hcomc_steps_per_s": round(hcomc), "sumo_steps_per_s": round(sumo),
                     "plain_idm_steps_per_s": round(plain), "ratio": round(hcomc / sumo, 2),
                     "plain_idm_over_hcomc": round(plain / hcomc, 2)})  # fmt: skip
    return rows


def decisions(repeats: int) -> dict[str, Any]:
    """The default controller's decisions on the recorded problems: times and quality, each
    problem decided with the baseline's generators (its hypervolume is their mean), on every
    core (a main process scores a population's rows on all of numba's threads) and on one
    (as ``record_decisions.py`` and ``decision_latency.py`` measure by default), taking turns
    ``repeats`` times; the median of the passes' medians (and p95s) is reported, with every
    pass's median. Every problem's hypervolume must be the same in every pass (the tests hold
    the Pareto sets equal bit for bit)."""
    problems = load_decisions(PROBLEMS_FILE)
    baseline = json.loads(
        PROBLEMS_FILE.with_name(PROBLEMS_FILE.stem + "_baseline.json").read_text()
    )
    per_problem = baseline["decisions"] // baseline["problems"]
    threads = numba.get_num_threads()
    passes: dict[int, list[dict[str, Any]]] = {threads: [], 1: []}
    for k in range(repeats):
        for n, rows in passes.items():
            progress(f"decisions {k + 1}/{repeats}: {len(problems)} recorded problems x "
                     f"{per_problem}, {n} thread{'s' if n > 1 else ''}")  # fmt: skip
            numba.set_num_threads(n)
            try:
                rows.append(evaluate(problems, None, per_problem))
            finally:
                numba.set_num_threads(threads)
    first = passes[threads][0]
    if any(r["per_problem"] != first["per_problem"] for rows in passes.values() for r in rows):
        raise SystemExit("the decisions differ between passes or between thread counts")

    def summary(rows: list[dict[str, Any]]) -> dict[str, Any]:
        return {"median_ms": statistics.median(r["median_ms"] for r in rows),
                "p95_ms": statistics.median(r["p95_ms"] for r in rows),
                "max_ms": max(r["max_ms"] for r in rows),
                "pass_medians_ms": [r["median_ms"] for r in rows]}  # fmt: skip

    result = {key: first[key] for key in ("optimizer", "budget", "problems", "decisions",
                                          "with_feasible_front", "identical_to_first")}  # fmt: skip
    result.update(summary(passes[threads]))
    result["vs_baseline"] = against_baseline(first, baseline)
    result["threads"] = threads
    result["one_thread"] = summary(passes[1])
    return result


def phases(scene: str, n: int, repeats: int) -> str:
    """The step's cost model on ``scene``: ns per vehicle-step and its four largest phases."""
    progress(f"cost model: {scene} {n or ''}")
    row = measure(scene, n, DURATION, repeats)
    parts: dict[str, float] = row["ns_per_vehicle_step"]  # type: ignore[assignment]
    top = sorted(parts.items(), key=lambda kv: -kv[1])[:4]
    rate = float(row["rate"])  # type: ignore[arg-type]
    listed = ", ".join(f"{name} {ns:.0f}" for name, ns in top)
    return f"{scene} {row['vehicles']}: {1e9 / rate:.0f} ns a vehicle-step ({listed})"


def decision_split() -> str:
    """Where a decision's time goes (``decision_latency.py --split``), one decision of each
    recorded problem."""
    progress("cost model: decisions")
    part = split([(d.config, d.view, d.group) for d in load_decisions(PROBLEMS_FILE)], 1)
    return (f"a decision {part['decision_ms']} ms: NSGA-II's compiled search "
            f"{part['search_ms']} ms, of which the rollouts of its "
            f"{part['rows_per_decision']:.0f} candidate rows take {part['scoring_ms']} ms "
            f"({part['us_per_row']} us a row, scored again on their own) and NSGA-II's steps "
            f"the rest; the lane-change game {part['game_ms']} ms; the rest (set-up, selection, "
            f"the chosen plan's prediction) {part['rest_ms']} ms")  # fmt: skip


def per_core(batch: dict[str, Any]) -> str:
    """The ensemble's rate on one thread and the cores the target would take at that rate
    (every core as fast as one alone)."""
    one, sumo = batch["hcomc_one_thread_steps_per_s"], batch["sumo_steps_per_s"]
    cores = math.ceil(ENSEMBLE_RATIO * sumo / one)
    return (f"on one thread {one / 1e6:.2f} M vehicle-steps/s ({one / sumo:.1f}x SUMO), so "
            f"{ENSEMBLE_RATIO:g}x takes {cores} such cores")  # fmt: skip


def allowed(ratio: float, rate: float) -> int:
    """The ns a vehicle-step may take to run ``ratio`` times as fast as ``rate``
    [vehicle-steps/s]."""
    return round(1e9 / (ratio * rate))


def short_of(run: dict[str, Any], bound: float, repeats: int) -> str:
    """The step's cost model of a single run below its bound, with what the bound allows
    and, on the line, what the paper's car following alone takes."""
    budget = allowed(bound, run["sumo_steps_per_s"])
    model = phases(run["scene"], run["size"], repeats)
    floor = f" ({following_alone(run['size'], repeats)})" if run["scene"] == "line" else ""
    return f"{model} against the {budget} ns {bound:g}x SUMO allows{floor}"


def following_alone(n: int, repeats: int) -> str:
    """What the paper's car following alone takes on the line of ``n`` vehicles
    (``step_cost.py``'s ``paper_following``)."""
    progress(f"cost model: the paper's car following alone, line {n}")
    rate = paper_following_rate(line_config(n, DURATION), repeats)
    return f"the paper's car following alone, Eq. 2 and Eq. 1/3, takes {1e9 / rate:.0f} ns"


def idm_allowance(lines: list[dict[str, Any]]) -> str:
    """The ns a vehicle-step of the line may take within the plain IDM's factor, per size."""
    sizes = ", ".join(
        f"{allowed(1.0 / PLAIN_IDM_FACTOR, r['plain_idm_steps_per_s'])} ns at {r['size']}"
        for r in lines
    )
    return f"the {sizes} that {PLAIN_IDM_FACTOR:g}x the plain IDM's time allows"


def reproduce_cores(repro: dict[str, Any], most: int = 64) -> str:
    """What more cores would give the reproduction: the runs' seconds (the sum of their
    shares of their batches' time on the workers) spread over N workers, each core as fast as
    one of this run's, plus the rest of its wall time (start, workers' start, uneven ends,
    claims, report), which more cores do not shorten; the least N that meets the target."""
    wall, runs, workers = repro["hcomc_wall_s"], repro["hcomc_runs_wall_s"], repro["workers"]
    rest = max(wall - runs / workers, 0.0)
    bound = REPRODUCE_RATIO * repro["sumo_wall_s"]
    cores = next((n for n in range(1, most + 1) if rest + runs / n <= bound), None)
    reach = (
        f"so {REPRODUCE_RATIO:g}x takes {cores} such cores"
        if cores is not None
        else f"no number of such cores up to {most} reaches {REPRODUCE_RATIO:g}x"
    )
    return (f"its wall time is the runs' {runs} s over {workers} workers and {rest:.1f} s "
            f"besides them, {reach}")  # fmt: skip


def judge(
    runs: list[dict[str, Any]], batch: dict[str, Any] | None, decided: dict[str, Any] | None,
    repro: dict[str, Any] | None, repeats: int,
) -> list[Target]:  # fmt: skip
    """Each target against its bound; the cost model of those not met."""
    targets = []
    for n, bound in SIZES.items():
        of_size = [r for r in runs if r["size"] == n]
        met = all(r["ratio"] >= bound for r in of_size)
        slow = [short_of(r, bound, repeats) for r in of_size if r["ratio"] < bound]
        targets.append(Target(
            f"single run, {n} vehicles", f">= {bound:g}x SUMO, both scenes",
            ", ".join(f"{r['scene']} {r['ratio']}x" for r in of_size), met,
            "; ".join(slow)))  # fmt: skip
    lines = [r for r in runs if r["scene"] == "line"]
    met = all(r["plain_idm_over_hcomc"] <= PLAIN_IDM_FACTOR for r in lines)
    targets.append(Target(
        "the line's step", f"within {PLAIN_IDM_FACTOR:g}x the plain IDM's rate",
        ", ".join(f"{r['plain_idm_over_hcomc']}x at {r['size']}" for r in lines), met,
        "" if met else f"the line's cost model above, against {idm_allowance(lines)}"))  # fmt: skip
    if batch is not None:
        met = batch["ratio"] >= ENSEMBLE_RATIO
        targets.append(Target(
            f"ensemble of {batch['runs']} C1 runs", f">= {ENSEMBLE_RATIO:g}x SUMO's single run",
            f"{batch['ratio']}x on {batch['threads']} threads", met,
            "" if met else f"{phases('c1', 0, repeats)}; {per_core(batch)}"))  # fmt: skip
    if decided is not None:
        quality = decided["vs_baseline"]
        met = decided["median_ms"] <= DECISION_MS and quality["min_ratio"] >= EQUAL_QUALITY
        targets.append(Target(
            "one HCOMC decision", f"median <= {DECISION_MS:g} ms, equal quality",
            f"{decided['median_ms']} ms median (p95 {decided['p95_ms']}; passes "
            f"{', '.join(map(str, decided['pass_medians_ms']))}) on {decided['threads']} "
            f"threads, {decided['one_thread']['median_ms']} ms (p95 "
            f"{decided['one_thread']['p95_ms']}) on one; hypervolume "
            f"{quality['min_ratio']}-{quality['mean_ratio']} of the baseline (least, mean)", met,
            "" if met else decision_split()))  # fmt: skip
    if repro is not None:
        ratio = round(1.0 / repro["ratio"], 2)  # our time over SUMO's
        targets.append(Target(
            "hcomc reproduce, default", f"<= {REPRODUCE_RATIO:g}x SUMO's time",
            f"{ratio}x ({repro['hcomc_wall_s']} s against {repro['sumo_wall_s']} s)",
            ratio <= REPRODUCE_RATIO,
            f"{repro['hcomc_decisions_s']} s of the runs' {repro['hcomc_runs_wall_s']} s in "
            f"{repro['hcomc_decisions']:,} merge decisions ({largest(repro)}); "
            f"{reproduce_cores(repro)}"))  # fmt: skip
    return targets


def largest(repro: dict[str, Any], count: int = 3) -> str:
    """The configurations whose decisions took the most of the reproduction's time."""
    by_configuration = repro["hcomc_decisions_s_by_configuration"]
    return ", ".join(f"{name} {seconds} s" for name, seconds in
                     list(by_configuration.items())[:count])  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="alternating repetitions")
    parser.add_argument("--ensemble", type=int, default=100, help="C1 runs (0: skip)")
    parser.add_argument("--reproduce-seeds", type=int, default=30, help="0: skip the reproduction")
    parser.add_argument("--reproduce-workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--no-decisions", action="store_true", help="skip the decisions")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    counts = (args.ensemble, args.reproduce_seeds)
    if args.repeats < 1 or min(counts) < 0 or args.reproduce_workers < 1:
        parser.error("--repeats and --reproduce-workers must be >= 1, the other counts >= 0")
    stamp = {**machine(), "revision": git_revision(), "sumo": sumo_version(),
             "date": datetime.date.today().isoformat()}  # fmt: skip
    try:
        with tempfile.TemporaryDirectory(prefix="hcomc-targets-") as name:
            tmp = Path(name)
            runs = single_runs(args.repeats, tmp)
            batch = decided = repro = None
            if args.ensemble:
                progress(f"ensemble of {args.ensemble} C1 runs")
                batch = ensemble(args.ensemble, args.repeats, tmp)
            if not args.no_decisions:
                decided = decisions(args.repeats)
            if args.reproduce_seeds:
                progress(f"hcomc reproduce --seeds {args.reproduce_seeds}")
                repro = reproduce(args.reproduce_seeds, args.reproduce_workers, args.repeats, tmp)
    except (ConfigError, SumoMissingError, RuntimeError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
    targets = judge(runs, batch, decided, repro, max(args.repeats, 3))
    if args.json:
        print(json.dumps({"stamp": stamp, "single_runs": runs, "ensemble": batch,
                          "decisions": decided, "reproduce": repro,
                          "targets": [asdict(t) for t in targets]}))  # fmt: skip
        return
    print("stamp:", ", ".join(f"{k} {v}" for k, v in stamp.items()))
    for r in runs:
        print(f"{r['scene']} {r['size']}: vehicle-steps/s hcomc {r['hcomc_steps_per_s']:,}, "
              f"SUMO {r['sumo_steps_per_s']:,}, "
              f"plain IDM {r['plain_idm_steps_per_s']:,}")  # fmt: skip
    print("\n| target | bound | measured | met | where the time goes |\n|---|---|---|---|---|")
    for t in targets:
        print(f"| {t.name} | {t.bound} | {t.measured} | {'yes' if t.met else 'no'} | {t.where} |")


if __name__ == "__main__":
    main()
