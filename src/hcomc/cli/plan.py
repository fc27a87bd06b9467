"""``hcomc plan``: the first merge decision of a scenario, with what the controller weighed
(HCOMC: the key vehicles, the lane-change game and the Pareto set)."""

from __future__ import annotations

import json
import sys
from typing import Annotated, Any

import typer
from rich.markup import escape
from rich.table import Table

from hcomc.cli._app import (
    ConfigArg,
    Optimizer,
    SeedOption,
    SetOption,
    _check_seed,
    _compiled,
    _control,
    _fail,
    _load,
    _require_merge,
    _settings,
    _with,
    app,
    out,
)


@app.command()
def plan(
    config: ConfigArg,
    seed: SeedOption = None,
    optimizer: Optimizer = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print the decision as JSON.")] = False,
    settings: SetOption = None,
    controller: Annotated[
        str,
        typer.Option(
            help="Merge controller: hcomc, fifo, game, another registered name, "
            "package.module:Class or path/to/file.py:Class."
        ),
    ] = "hcomc",
) -> None:
    """Run until the first ramp vehicle enters the control zone and show the controller's
    decision (HCOMC: with its lane-change game and Pareto set)."""
    from hcomc.control.report import plan_report
    from hcomc.sim.engine import Simulation

    _check_seed(seed)
    overrides = _settings(settings)
    base = _load(config, **overrides)
    _require_merge(base, config, "plan")
    control = _control(base.control, controller, optimizer)
    if control["controller"] == "none":
        raise _fail("option '--controller' = 'none': allowed: a merge controller")
    cfg = _load(config, **_with(overrides, seed=seed, control=control))
    _compiled()
    sim = Simulation(cfg)
    decision = sim.run_until_plan()
    if decision is None:
        raise _fail(
            f"no ramp vehicle entered the control zone within duration = {cfg.duration} s "
            f"of '{config}'; allowed: a longer --set duration=... or an earlier ramp release"
        )
    report = plan_report(sim, decision)
    if as_json:
        sys.stdout.write(json.dumps(report) + "\n")
    else:
        _print_plan(report)


def _print_plan(report: dict[str, Any]) -> None:
    if not report["n_eval"]:  # a controller without HCOMC's optimisation
        _print_other_plan(report)
        return
    out.print(
        f"[bold]{report['scenario']}[/] seed {report['seed']} · t = {report['t']:.1f} s · "
        f"optimiser {report['optimizer']} · {report['n_eval']} evaluations · "
        f"decision {report['decision_ms']:.1f} ms"
    )
    out.print(_key_table(report))
    game = report["game"]
    if game:
        verdict = "admitted" if game["lateral_allowed"] else "not admitted"
        out.print(f"lane-change game (VMC vs VNR): {game['reason']}; lateral mode {verdict}")
    pareto = Table(title="Pareto set (feasible, non-dominated)")
    cols = (
        "#",
        "merge x [m]",
        "VR T_lc [s]",
        "H [s]",
        "mode",
        "VR vs VMC",
        "U_safe [m/s²]",
        "U_fuel [L]",
        "−U_eff [m/s²]",
    )
    for col in cols:
        pareto.add_column(col, justify="right")
    chosen = report["chosen"]
    for i, p in enumerate(report["pareto"]):
        mark = "★ " if chosen and i == chosen["index"] else ""
        pareto.add_row(
            f"{mark}{i}",
            f"{p['merge_x']:.1f}",
            f"{p['vr_duration']:.2f}",
            f"{p['horizon']:.2f}",
            p["mode"][:3],
            p["sequence"],
            f"{p['safety']:.3f}",
            f"{p['fuel']:.4f}",
            f"{p['efficiency']:.3f}",
        )
    out.print(pareto)
    if chosen is None:
        out.print(f"[yellow]fallback:[/] {report['reason']}")
    else:
        out.print(
            f"chosen (Eq. 19, {report['eq19_branch']} branch): #{chosen['index']} · mode "
            f"[bold]{report['mode']}[/] · VR {report['sequence']} of VMC · "
            f"merge at {chosen['merge_x']:.1f} m, T_lc {chosen['vr_duration']:.2f} s, "
            f"H {chosen['horizon']:.2f} s"
        )


def _key_table(report: dict[str, Any]) -> Table:
    keys = Table(title="key vehicles (Section II-A)")
    for col in ("role", "id", "kind", "lane", "x [m]", "v [m/s]"):
        keys.add_column(col, justify="right")
    for role, k in report["key_vehicles"].items():
        if k is None:
            keys.add_row(role, "—", "—", "—", "—", "—")
        else:
            keys.add_row(
                role, str(k["id"]), k["kind"], str(k["lane"]), f"{k['x']:.1f}", f"{k['v']:.2f}"
            )
    return keys


def _print_other_plan(report: dict[str, Any]) -> None:
    """The decision of a controller other than HCOMC: key vehicles and the plan's fields."""
    out.print(
        f"[bold]{escape(report['scenario'])}[/] seed {report['seed']} · t = {report['t']:.1f} s "
        f"· controller {escape(report['controller'])} · decision {report['decision_ms']:.1f} ms"
    )
    out.print(_key_table(report))
    what = "fallback" if report["fallback"] else "plan"
    out.print(
        escape(
            f"{what}: mode {report['mode']} · VR {report['sequence']} of VMC · merge at "
            f"{report['merge_x']:.1f} m, T_lc {report['vr_duration']:.2f} s, H "
            f"{report['horizon']:.2f} s · {report['reason']}"
        ),
        highlight=False,
    )
