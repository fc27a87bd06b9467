"""``hcomc reproduce`` (the paper's experiments) and ``hcomc docs`` (the published
documentation regenerated from a reproduction's results)."""

from __future__ import annotations

import json
import time
from dataclasses import replace
from functools import partial
from pathlib import Path
from typing import Annotated, Any, cast

import typer

from hcomc.cli._app import (
    Engine,
    SetOption,
    _engine,
    _fail,
    _load,
    _refuse_overwrite,
    _settings,
    app,
    out,
)
from hcomc.cli.experiments import CONDITIONS, _progress_grid, _workers
from hcomc.cli.run_output import print_frame
from hcomc.config import ConfigError

CONTOUR_CONDITION = "C2"
"""The condition of the recorded scene: the report's and the README's speed contour maps (the
paper's Fig. 2) and the other gallery images."""


def _write_report(out_dir: Path, runs: Any, claim_frame: Any, contour: Any) -> Path:
    """results/report.html with the tables, claims, Fig. 2 (``contour``: the PNG of
    :func:`hcomc.viz.gallery.record_scene` for the first seed, or the exception it raised in
    its worker, raised here once the tables are saved) and the metric plots."""
    from hcomc.viz.figures import metrics_figure
    from hcomc.viz.gallery import REPLAY_FILE, SCENE_DIR
    from hcomc.viz.page import figure_png
    from hcomc.viz.report import write_report

    if isinstance(contour, BaseException):
        raise contour

    seed = int(runs["seed"].min())
    figures = {
        f"Speed contour maps of both lanes as in the paper's Fig. 2: Condition 2, seed {seed}, "
        "FIFO, Game and HCOMC":
            contour,
        "The paper's metrics by condition and configuration (mean, 95 % CI over seeds; a "
        "bar marked n=k rests on the k seeds that give a value)":
            figure_png(metrics_figure(runs)),
    }  # fmt: skip
    replays = {
        f"Condition 2, seed {seed}: FIFO, Game and HCOMC side by side (interactive replay)":
            f"{SCENE_DIR}/{REPLAY_FILE}",
    }  # fmt: skip
    return write_report(out_dir, runs, figures=figures, claim_frame=claim_frame, replays=replays)


PAPER_SCENARIO: dict[str, dict[str, Any]] = {
    "demand": {"pattern": "uniform"},
    "hdv": {"estimation_errors": False},
}
"""Overrides of the deterministic paper scenario: every headway equal to its mean, CAVs
spread evenly, no HDV estimation errors (reaction delays stay); seed 0 seeds the optimisers."""


def _claims_view(frame: Any) -> Any:
    """The claims for the terminal: the verdicts (CI rule, Holm-corrected sign test) with
    "k of n seeds" beside them, the median and its CI rounded to the CI's precision."""
    from hcomc.experiments.comparison.view import interval_text

    view = frame[["claim", "condition"]].rename(columns={"condition": "cell"})
    view["median A-B [95 % CI]"] = [
        interval_text(m, lo, hi)
        for m, lo, hi in zip(frame["median_diff"], frame["ci_low"], frame["ci_high"], strict=True)
    ]
    view["verdict"] = frame["verdict"]
    view["p (Holm)"] = [f"{p:.2g}" for p in frame["p_holm"]]
    view["verdict (Holm)"] = frame["verdict_holm"]
    view["seeds"] = [f"{k} of {n}" for k, n in zip(frame["holds"], frame["n"], strict=True)]
    if "uniform" in frame:
        view["uniform"] = frame["uniform"]
    return view


CLAIMS_CAPTION = (
    "median of the paired differences A - B [95 % bootstrap CI]; verdict: the CI rule; "
    "verdict (Holm): the sign test (a run without a merge the worst outcome), Holm-corrected "
    "within the claim's family; seeds: k of n seeds in the paper's direction; uniform: "
    "whether the claim holds on the paper scenario's deterministic runs (one per "
    "configuration; empty where it is undefined there, e.g. a metric of a merge that did not "
    "happen)"
)
"""The legend of the claims table on the terminal."""

SCENARIO_CAPTION = (
    "deterministic demand: every headway its mean, CAVs spread evenly, no estimation errors "
    "of human drivers; merged no: VR waited at the end of the acceleration lane until the run "
    "ended, so the merge has no metrics (—) and no cooperation mode (none)"
)
"""The legend of the paper-scenario table on the terminal."""


def _verdict_line(frame: Any) -> str:
    """How many claims of each Holm family hold, are reversed and undecided, by both verdict
    columns (the paper's claims, the merge outcomes, the replanning variants', HCOMC+'s)."""
    from hcomc.experiments.claim_text import families_line

    return families_line(frame)


REPRODUCE_FILES = ("runs.csv", "claims.csv", "table2.md", "table3.md")


def _command(
    seeds: int, out_dir: Path, settings: list[str] | None, engine: str, extra: list[str]
) -> str:
    """The command line of a reproduction (what its results depend on; not --workers)."""
    import shlex

    parts = ["hcomc", "reproduce", "--seeds", str(seeds), "--out", str(out_dir)]
    for pair in settings or []:
        parts += ["--set", pair]
    if engine != "hcomc":
        parts += ["--engine", engine]
    if extra:
        parts += ["--controllers", ",".join(extra)]
    return shlex.join(parts)


def _save_results(out_dir: Path, runs: Any, paper_runs: Any, claim_rows: Any, record: dict) -> None:
    """The results files of a reproduction, written atomically."""
    from hcomc.experiments.digest import RUN_RECORD
    from hcomc.experiments.tables import paper_table, to_markdown
    from hcomc.sim.manifest import atomic_paths, json_default

    names = ("runs.csv", "runs.parquet", "table2.md", "table3.md", "claims.csv",
             "paper_scenario.csv", RUN_RECORD)  # fmt: skip
    with atomic_paths(*(out_dir / n for n in names)) as tmp:
        runs.to_csv(tmp[0], index=False)
        runs.to_parquet(tmp[1], index=False)
        tmp[2].write_text(to_markdown(paper_table(runs, "II")), encoding="utf-8")
        tmp[3].write_text(to_markdown(paper_table(runs, "III")), encoding="utf-8")
        claim_rows.to_csv(tmp[4], index=False)
        paper_runs.to_csv(tmp[5], index=False)
        tmp[6].write_text(json.dumps(record, indent=2, default=json_default) + "\n", "utf-8")


def _print_results(runs: Any, paper_runs: Any, claim_rows: Any) -> None:
    from hcomc.experiments.comparison.view import rounded
    from hcomc.experiments.paper import PAPER_METRICS
    from hcomc.experiments.tables import LABELS, TABLE_CAPTION, paper_table

    print_frame(paper_table(runs, "II"), "Table II — optimisers", TABLE_CAPTION, keys=2)
    print_frame(paper_table(runs, "III"), "Table III — controllers", TABLE_CAPTION, keys=2)
    scenario = paper_runs[["condition", "configuration", "merged", "mode", "sequence",
                           *PAPER_METRICS]]  # fmt: skip
    view = scenario.assign(
        merged=scenario["merged"].map({True: "yes", False: "no"}),
        **{m: [rounded(v) for v in scenario[m]] for m in PAPER_METRICS},
    ).rename(columns=LABELS)
    print_frame(view, "Paper scenario — one run per configuration", SCENARIO_CAPTION, keys=2)
    print_frame(_claims_view(claim_rows), "Claims of Section IV", CLAIMS_CAPTION, keys=2)


def _publish(out_dir: Path, docs: Path | None, readme: Path | None, force: bool) -> None:
    """Regenerate the documentation of a results directory and name every file written."""
    from hcomc.viz.publish import write_docs

    if docs is None:
        return
    try:
        written = write_docs(out_dir, docs, readme=readme, force=force)
    except ValueError as exc:
        raise _fail(str(exc)) from None
    out.print(f"documentation regenerated from {out_dir}/: " + ", ".join(map(str, written)))


def _docs_targets(docs: Path | None, readme: Path | None, force: bool) -> Path | None:
    """Check a documentation directory before anything runs; return the README to update
    (the given one, else the README.md next to ``docs`` if there is one)."""
    from hcomc.viz.publish import Targets, check_targets, default_readme

    if docs is None:
        if readme is not None:
            raise _fail(f"option '--readme' = '{readme}' applies only with '--docs'")
        return None
    readme = readme if readme is not None else default_readme(docs)
    try:
        check_targets(Targets(docs, readme), force)
    except ValueError as exc:
        raise _fail(str(exc)) from None
    return readme


DocsOption = Annotated[
    Path | None,
    typer.Option(
        "--docs",
        help="After the run, regenerate the documentation in this directory (e.g. docs): "
        "reproduction.md, data/, img/ and the README block.",
    ),
]
ReadmeOption = Annotated[
    Path | None,
    typer.Option(
        help="README whose generated block is replaced (default: README.md next to the docs "
        "directory, if there is one)."
    ),
]


def _own_controllers(names: str | None) -> list[str]:
    """``--controllers``: controller names of the user's, each checked (imported) now."""
    from hcomc.experiments.runner import ALL_CONFIGURATIONS, configuration_label

    if names is None:
        return []
    labels = []
    for name in (n.strip() for n in names.split(",")):
        try:
            label = configuration_label(name) if name else ""
        except ConfigError as exc:
            message = str(exc).replace("key 'control.controller'", "option '--controllers'", 1)
            raise _fail(message) from None
        if not label or label in ALL_CONFIGURATIONS:
            raise _fail(
                f"option '--controllers' = '{names}': '{name}' is "
                + ("empty" if not name else "one of the paper's configurations, run anyway")
                + "; allowed: controllers of your own, comma-separated"
            )
        labels.append(label)
    return labels


@app.command()
def reproduce(
    seeds: Annotated[int, typer.Option(help="Seeds per condition and configuration.")] = 30,
    workers: Annotated[int | None, typer.Option(help="Processes (default: all cores).")] = None,
    out_dir: Annotated[Path, typer.Option("--out", help="Output directory.")] = Path("results"),
    force: Annotated[
        bool, typer.Option("--force", help="Overwrite results already in the --out directory.")
    ] = False,
    settings: SetOption = None,
    engine: Engine = "hcomc",
    docs: DocsOption = None,
    readme: ReadmeOption = None,
    controllers: Annotated[
        str | None,
        typer.Option(
            help="Controllers of your own run beside the paper's configurations, comma-"
            "separated (a registered name, package.module:Class or path/to/file.py:Class); "
            "their rows join runs.csv, the report and a paired comparison with FIFO, Game "
            "and HCOMC."
        ),
    ] = None,
) -> None:
    """Reproduce the paper: Table I conditions x (FIFO, Game, HCOMC with NSGA-II, PSO, SA,
    all planning once as published; the replanning variants FIFO-R, Game-R, HCOMC-R and the
    labelled extension HCOMC+, the equilibrium-only HCOMC-eq), seeded runs
    plus the deterministic paper scenario. --set changes a config value for every run (e.g. a
    sensitivity check); --controllers adds controllers of your own; --docs regenerates the
    published documentation from the run."""
    from hcomc.config import nest_overrides
    from hcomc.experiments.claims import claims
    from hcomc.experiments.runner import ALL_CONFIGURATIONS, grid
    from hcomc.sim.manifest import write_json_atomic
    from hcomc.viz.gallery import record_scene

    if seeds < 1:
        raise _fail(f"option '--seeds' = {seeds}: must be >= 1")
    _refuse_overwrite(out_dir, REPRODUCE_FILES, force)
    extra = _own_controllers(controllers)
    if extra and docs is not None:
        raise _fail(
            f"option '--docs' = '{docs}' publishes the paper's configurations only; allowed: "
            "--docs or --controllers, not both"
        )
    readme = _docs_targets(docs, readme, force=False)
    overrides = nest_overrides(_settings(settings))
    for condition in CONDITIONS:  # validate before anything runs
        _load(condition, **overrides)
    n_workers, engine = _workers(workers), _engine(engine)
    start = time.perf_counter()
    seeded = [
        replace(s, engine=engine)
        for s in grid(CONDITIONS, [*ALL_CONFIGURATIONS, *extra], range(seeds), overrides)
    ]
    paper = {**overrides}
    for table, values in PAPER_SCENARIO.items():
        paper[table] = {**cast(dict[str, Any], overrides.get(table, {})), **values}
    uniform = [
        replace(s, engine=engine)
        for s in grid(CONDITIONS, [*ALL_CONFIGURATIONS, *extra], [0], paper)
    ]
    (out_dir / "manifests").mkdir(parents=True, exist_ok=True)

    def save_manifest(i: int, row: dict[str, Any], manifest: dict[str, Any]) -> None:
        tag = f"seed{row['seed']}" if i < len(seeded) else "uniform"
        name = f"{row['condition']}-{row['configuration']}-{tag}.json"
        write_json_atomic(out_dir / "manifests" / name, manifest)

    # the scene (report's Fig. 2, gallery) is recorded by a worker while the last runs finish
    contour: dict[int, Any] = {}  # the PNG, or the exception recording it raised
    scene = partial(
        record_scene, out_dir, CONTOUR_CONDITION, min(s.seed for s in seeded), overrides
    )
    both = _progress_grid(
        [*seeded, *uniform], n_workers, on_result=save_manifest, after=[scene],
        on_after=contour.__setitem__,
    )  # fmt: skip
    runs = both.iloc[: len(seeded)].reset_index(drop=True)
    paper_runs = both.iloc[len(seeded) :].reset_index(drop=True)
    claim_rows = claims(runs, paper_runs)
    wall = time.perf_counter() - start
    record = {
        "command": _command(seeds, out_dir, settings, engine, extra),
        "seeds": seeds,
        "overrides": overrides,
        "engine": engine,
        "workers": n_workers,
        "wall_s": wall,
    }
    _save_results(out_dir, runs, paper_runs, claim_rows, record)
    report = _write_report(out_dir, runs, claim_rows, contour[0])
    _print_results(runs, paper_runs, claim_rows)
    out.print(f"report: {report}")
    out.print(
        f"{_verdict_line(claim_rows)} · {len(runs)} seeded runs and {len(paper_runs)} of the "
        f"paper scenario · {n_workers} workers · {wall:.1f} s "
        f"· written to {out_dir}/"
    )
    from hcomc.experiments.claim_text import seeds_sentence

    if few := seeds_sentence(seeds):  # a quick look: too few seeds to decide any claim
        out.print(few)
    _publish(out_dir, docs, readme, force=False)


@app.command(name="docs")
def docs_command(
    results: Annotated[
        Path, typer.Argument(metavar="RESULTS", help="A results directory of 'hcomc reproduce'.")
    ],
    out_dir: Annotated[Path, typer.Option("--out", help="Documentation directory (e.g. docs).")],
    readme: ReadmeOption = None,
    force: Annotated[
        bool,
        typer.Option("--force", help="Replace a reproduction.md that 'hcomc docs' did not write."),
    ] = False,
) -> None:
    """Regenerate the published documentation from a reproduction's results, without
    simulating: reproduction.md, its data/ summary, the img/ gallery and the README block."""
    readme = _docs_targets(out_dir, readme, force)
    _publish(results, out_dir, readme, force)
