"""NSGA-II Pareto set in objective space and the plans every optimiser chose."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from matplotlib.ticker import MaxNLocator

from hcomc.viz.common import (
    MODE_COLORS,
    new_figure,
)

if TYPE_CHECKING:
    from matplotlib.figure import Figure


_PROJECTIONS = (("safety", "fuel"), ("safety", "efficiency"), ("fuel", "efficiency"))
_OBJECTIVE_LABELS = {
    "safety": "$U_{safe}$ [m/s²]",
    "fuel": "$U_{fuel}$ [L]",
    "efficiency": "$-U_{eff}$ [m/s²]",
}
_OPTIMIZER_NAMES = {"nsga2": "NSGA-II", "pso": "PSO", "sa": "SA"}
_OPTIMIZER_MARKERS = {"pso": ("D", "#17becf"), "sa": ("^", "#e377c2")}
_OTHER_MARKERS = (("s", "#8c564b"), ("P", "#7f7f7f"), ("X", "#bcbd22"), ("v", "#9467bd"))


def _pick_front(reports: Mapping[str, Mapping[str, Any]]) -> str:
    """Key of the report whose Pareto set is drawn: NSGA-II if present, else the largest."""
    for key, rep in reports.items():
        if str(key).lower() == "nsga2" or str(rep.get("optimizer", "")).lower() == "nsga2":
            return key
    return max(reports, key=lambda k: len(reports[k].get("pareto") or []))


def pareto_figure(
    reports: Mapping[str, Mapping[str, Any]], *, safety_threshold: float | None = None
) -> Figure:
    """Pairwise projections of the Pareto set of one merge decision.

    Three panels: U_safe-U_fuel, U_safe-(-U_eff) and U_fuel-(-U_eff) (all minimised). The
    feasible Pareto set of the NSGA-II report is scattered, coloured by VMC's cooperation
    mode; its Eq. 19 choice is a gold star; the chosen solutions of the other optimisers
    (PSO, SA ...) are distinct markers; the Eq. 19 safety gate is a dashed line.

    Parameters
    ----------
    reports : mapping of str to dict
        Optimiser name (``"nsga2"``, ``"pso"``, ``"sa"`` ...) -> plan report of
        :func:`hcomc.control.report.plan_report` for the same decision (same scenario and
        seed).
    safety_threshold : float or None
        U_safe gate of Eq. 19 [m/s^2]; default: the ``control.safety_threshold`` the
        decision ran with, recorded in its report.

    Returns
    -------
    matplotlib.figure.Figure
        3 axes.

    Raises
    ------
    ValueError
        If *reports* is empty, or no threshold is given and a report does not record one.
    """
    if not reports:
        raise ValueError("pareto_figure needs at least one plan report, got none")
    front_key = _pick_front(reports)
    front = reports[front_key]
    if safety_threshold is None:
        if "safety_threshold" not in front:
            raise ValueError(
                f"plan report '{front_key}' does not record its safety_threshold "
                "(written by an older hcomc): pass safety_threshold=..."
            )
        safety_threshold = float(front["safety_threshold"])
    pareto = list(front.get("pareto") or [])
    fig = new_figure(13.0, 4.6)
    axes = fig.subplots(1, 3)
    front_name = _OPTIMIZER_NAMES.get(str(front.get("optimizer", front_key)).lower(), front_key)
    for ax, (fx, fy) in zip(axes, _PROJECTIONS, strict=True):
        for mode in MODE_COLORS:
            pts = [p for p in pareto if p.get("mode") == mode]
            if pts:
                ax.scatter(
                    [p[fx] for p in pts],
                    [p[fy] for p in pts],
                    s=22,
                    color=MODE_COLORS[mode],
                    alpha=0.75,
                    edgecolors="white",
                    linewidths=0.4,
                    zorder=2,
                    label=f"{front_name} Pareto set, {mode}",
                )
        chosen = front.get("chosen")
        if chosen:
            ax.plot(
                [chosen[fx]],
                [chosen[fy]],
                linestyle="none",
                marker="*",
                markersize=17,
                markerfacecolor="gold",
                markeredgecolor="black",
                zorder=5,
                label=f"{front_name} chosen (Eq. 19)",
            )
        others = [k for k in reports if k != front_key]
        for j, key in enumerate(others):
            rep = reports[key]
            opt = str(rep.get("optimizer", key)).lower()
            marker, color = _OPTIMIZER_MARKERS.get(opt, _OTHER_MARKERS[j % len(_OTHER_MARKERS)])
            ch = rep.get("chosen")
            if ch:
                ax.plot(
                    [ch[fx]],
                    [ch[fy]],
                    linestyle="none",
                    marker=marker,
                    markersize=9,
                    markerfacecolor=color,
                    markeredgecolor="black",
                    zorder=4,
                    label=f"{_OPTIMIZER_NAMES.get(opt, key)} chosen",
                )
        if fx == "safety":
            lo, hi = ax.get_xlim()
            pad = 0.05 * (hi - lo)
            lo, hi = min(lo, safety_threshold - pad), max(hi, safety_threshold + pad)
            ax.axvspan(
                safety_threshold,
                hi,
                color="#b2182b",
                alpha=0.06,
                linewidth=0,
                label="penalised by Eq. 19 ($U_{safe}$ above the gate)",
            )
            ax.set_xlim(lo, hi)
            ax.axvline(
                safety_threshold,
                color="#b2182b",
                linewidth=1.1,
                linestyle=(0, (5, 3)),
                label=f"safety gate $U_{{safe}}$ = {safety_threshold:g} m/s²",
            )
        ax.set_xlabel(_OBJECTIVE_LABELS[fx])
        ax.set_ylabel(_OBJECTIVE_LABELS[fy])
        ax.set_title(f"{_OBJECTIVE_LABELS[fx].split()[0]} vs {_OBJECTIVE_LABELS[fy].split()[0]}")
        ax.grid(True, color="0.88", linewidth=0.5)
        ax.xaxis.set_major_locator(MaxNLocator(5))
    handles, labels = axes[0].get_legend_handles_labels()
    h2, l2 = axes[2].get_legend_handles_labels()
    for h, lab in zip(h2, l2, strict=True):
        if lab not in labels:
            handles.append(h)
            labels.append(lab)
    fig.legend(
        handles,
        labels,
        loc="outside lower center",
        ncols=min(len(labels), 4),
        fontsize=8,
        frameon=False,
    )
    scenario, seed, t = front.get("scenario"), front.get("seed"), front.get("t")
    facts = [str(scenario)] if scenario else []
    if seed is not None:
        facts.append(f"seed {seed}")
    if t is not None:
        facts.append(f"t = {float(t):.1f} s")
    facts.append(f"{len(pareto)} feasible Pareto solutions")
    fig.suptitle("Pareto set of the merge decision — " + " · ".join(facts))
    return fig
