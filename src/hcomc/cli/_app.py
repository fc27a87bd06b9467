"""The ``hcomc`` typer app and what its commands share: options, input checks, errors."""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn
from typer.core import TyperGroup

from hcomc.config import ConfigError, ControlParams, ScenarioConfig, load_config

UsageError: type[Exception] = next(
    c for c in typer.BadParameter.__mro__ if c.__name__ == "UsageError"
)
"""click's error for a command line it cannot parse, found from typer's public
``BadParameter``: recent typer releases carry their own copy of click (``typer._click``), older
ones use click itself."""


class _Commands(TyperGroup):
    """The command group: a command line click cannot parse, a config that cannot be
    realised, a controller's plan that fails its checks, or a controller that raises, is a
    one-line error in one style (``error: ...``, as every command's own checks print them),
    exit 2.

    Loading checks most of a config; what only shows when a run is set up (a log larger
    than ``log_memory_limit``, for one) raises :class:`~hcomc.config.ConfigError` later, in
    any command, and is reported here the same way instead of as a traceback; so is an
    :class:`~hcomc.control.validation.InvalidPlan` (with ``control.on_invalid_plan =
    "error"``) and a :class:`~hcomc.control.validation.ControllerFailed` (the controller,
    VR, time, scenario and seed), also when a worker process raised it. ``hcomc --traceback``
    prints the controller's own traceback first.
    """

    def make_context(
        self, info_name: str | None, args: list[str], parent: Any = None, **extra: Any
    ) -> Any:
        """click's, with an unparsable command line (``hcomc --bogus``) in our style."""
        try:
            return super().make_context(info_name, args, parent, **extra)
        except UsageError as exc:
            raise _fail(_usage(exc)) from None

    def invoke(self, ctx: Any) -> Any:  # ctx: typer's click Context
        from hcomc.control.validation import ControllerFailed, InvalidPlan

        try:
            return super().invoke(ctx)
        except UsageError as exc:  # a command or its options and arguments
            raise _fail(_usage(exc)) from None
        except (ConfigError, InvalidPlan) as exc:
            raise _fail(str(exc)) from None
        except ControllerFailed as exc:
            if (ctx.obj or {}).get("traceback"):
                err.print(exc.trace.rstrip(), highlight=False, markup=False, soft_wrap=True)
                raise _fail(str(exc)) from None
            raise _fail(f"{exc}; hcomc --traceback ... shows its traceback") from None


app = typer.Typer(
    cls=_Commands,
    name="hcomc",
    help="Cooperative on-ramp merging (HCOMC) in mixed traffic on two-lane highways.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,  # plain help: flags shown as flags, "[s]" units kept literally
    context_settings={"help_option_names": ["-h", "--help"]},
)
config_app = typer.Typer(help="Inspect scenario configs.", no_args_is_help=True)
app.add_typer(config_app, name="config")

# piped output (files, CI logs) gets wide tables instead of rich's 80-column default
out = Console(width=None if sys.stdout.isatty() else 200)
err = Console(stderr=True, width=None if sys.stderr.isatty() else 200)

OPTIMIZERS = ("nsga2", "nsga2-pymoo", "pso", "pso-pymoo", "sa", "sa-scipy")

ConfigArg = Annotated[
    str,
    typer.Argument(
        metavar="CONFIG", help="Preset name (C1..C5, platoon) or path to a TOML config file."
    ),
]
SetOption = Annotated[
    list[str] | None,
    typer.Option(
        "--set",
        metavar="KEY=VALUE",
        help="Override a config value, e.g. --set cav_penetration=0.5 or "
        "--set demand.mean_headway_main_2=7 (repeatable; VALUE is read as TOML).",
    ),
]
SeedOption = Annotated[int | None, typer.Option(help="Random seed (default: the config's).")]
Optimizer = Annotated[
    str | None,
    typer.Option(
        help="HCOMC optimiser: nsga2, nsga2-pymoo, pso, pso-pymoo, sa or sa-scipy (default: the "
        "config's)."
    ),
]


def _show_version(value: bool) -> None:
    if value:
        from hcomc import __version__

        out.print(f"hcomc {__version__}", highlight=False)
        raise typer.Exit()


@app.callback()
def _main(
    ctx: typer.Context,
    version: Annotated[
        bool,
        typer.Option(
            "--version", callback=_show_version, is_eager=True, help="Print the version and exit."
        ),
    ] = False,
    traceback: Annotated[
        bool,
        typer.Option(
            "--traceback", help="When a controller raises, print its traceback, not one line."
        ),
    ] = False,
) -> None:
    """Cooperative on-ramp merging (HCOMC) in mixed traffic on two-lane highways."""
    ctx.ensure_object(dict)["traceback"] = traceback


class _ProgressLines:
    """Progress as lines on stderr, for output that is not a terminal (a log, CI): one line
    at each tenth of the way and at the end, ``label: done/total (p %), elapsed, about T
    left``."""

    def __init__(self, label: str) -> None:
        self.label, self.start, self.tenths = label, time.perf_counter(), 0

    def __call__(self, done: int, total: int) -> None:
        tenths = 10 * done // max(total, 1)
        if tenths <= self.tenths and done < total:
            return
        self.tenths = tenths
        elapsed = time.perf_counter() - self.start
        left = elapsed * (total - done) / done if done else math.nan
        err.print(
            f"{self.label}: {done}/{total} ({100 * done / max(total, 1):.0f} %), "
            f"{_duration(elapsed)} elapsed"
            + (f", about {_duration(left)} left" if done < total and math.isfinite(left) else ""),
            highlight=False,
            markup=False,
        )
        if done >= total:
            self.tenths = 11  # the end is said once


def _duration(seconds: float) -> str:
    """A duration in words: "42 s", "3 min 05 s", "1 h 02 min"."""
    s = round(seconds)
    if s < 60:
        return f"{s} s"
    if s < 3600:
        return f"{s // 60} min {s % 60:02d} s"
    return f"{s // 3600} h {s % 3600 // 60:02d} min"


@contextmanager
def _progress(label: str, total: int) -> Iterator[Callable[[int, int], None] | None]:
    """A progress callback ``(done, total)``: on a terminal a bar with the counts and the time
    left; otherwise (a log, CI) :class:`_ProgressLines` on stderr, so that a long wait shows
    its progress either way and stdout keeps only the command's output."""
    if not out.is_terminal:
        yield _ProgressLines(label)
        return
    with Progress(
        TextColumn(f"[bold]{escape(label)}"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total}"),
        TimeRemainingColumn(),
        console=out,
        transient=True,
    ) as bar:
        task = bar.add_task(label, total=total)
        yield lambda done, _total: bar.update(task, completed=done)


def _compiled(*stages: str) -> None:
    """Compile the kernels of ``stages`` (default: those of the paper's scenarios) now, with a
    line per stage, if this environment has not (:func:`hcomc.cli._compile.ensure_compiled`);
    called once a command's input is checked, before it simulates. The lines go to the
    process's own stderr: they are about the environment, not part of the command's output
    (which a caller may capture and parse)."""
    from hcomc.cli._compile import SCENARIO, ensure_compiled

    ensure_compiled(Console(file=sys.__stderr__) if sys.__stderr__ else err, stages or SCENARIO)


def _usage(exc: Exception) -> str:
    """click's message of a command line it cannot parse (a :data:`UsageError`), with where
    to find what is allowed."""
    ctx = getattr(exc, "ctx", None)
    path = ctx.command_path if ctx is not None else "hcomc"
    message = exc.format_message() if hasattr(exc, "format_message") else str(exc)
    return f"{message.rstrip('.')} ({path} -h lists what is allowed)"


def _fail(message: str) -> typer.Exit:
    err.print(f"[bold red]error:[/] {escape(message)}", highlight=False, soft_wrap=True)
    return typer.Exit(code=2)


def _load(source: str, **overrides: Any) -> ScenarioConfig:
    try:
        return load_config(source, **overrides)
    except ConfigError as exc:
        raise _fail(str(exc)) from None


def _settings(pairs: list[str] | None) -> dict[str, Any]:
    """``--set KEY=VALUE`` pairs as overrides; VALUE is TOML (a bare word is a string)."""
    import tomllib

    settings: dict[str, Any] = {}
    for pair in pairs or []:
        key, sep, text = pair.partition("=")
        if not sep or not key.strip():
            raise _fail(f"option '--set' = '{pair}': allowed: KEY=VALUE, e.g. duration=60")
        try:
            value = tomllib.loads(f"v = {text.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            value = text.strip()
        settings[key.strip()] = value
    return settings


def _with(overrides: dict[str, Any], **options: Any) -> dict[str, Any]:
    """``--set`` overrides plus the command's own options (None = not given)."""
    given = {k: v for k, v in options.items() if v is not None}
    for key, value in given.items():
        if key in overrides and key != "control" and overrides[key] != value:
            raise _fail(
                f"option '--{key}' = {value} conflicts with '--set {key}={overrides[key]}'; "
                "allowed: one of them"
            )
    return {**overrides, **given}


def _choice(option: str, value: str | None, allowed: tuple[str, ...]) -> str | None:
    """``value`` lower-cased if it is one of ``allowed`` (names are case-insensitive)."""
    if value is None or value.lower() in allowed:
        return None if value is None else value.lower()
    key = f"control.{option.removeprefix('--')}"  # the config key the option sets
    raise _fail(f"option '{option}' = '{value}' ({key}): allowed: {', '.join(allowed)}")


def _check_seed(seed: int | None) -> None:
    if seed is not None and seed < 0:
        raise _fail(f"option '--seed' = {seed}: must be >= 0")


def _controller(value: str | None) -> str | None:
    """``--controller``: a registered name (case-insensitive), ``package.module:Class`` or
    ``path/to/file.py:Class``, checked (imported) before anything runs."""
    from hcomc.control.registry import canonical_name

    if value is None:
        return None
    try:
        return canonical_name(value)
    except ConfigError as exc:
        message = str(exc).replace("key 'control.controller'", "option '--controller'", 1)
        raise _fail(message) from None


def _control(base: ControlParams, controller: str | None, optimizer: str | None) -> dict:
    """The ``[control]`` table ``base`` with the command's controller/optimiser; an optimiser
    only applies to HCOMC, so passing one to another controller is an error, not ignored."""
    controller = _controller(controller)
    optimizer = _choice("--optimizer", optimizer, OPTIMIZERS)
    control = base.model_dump()
    control.update({k: v for k, v in (("controller", controller), ("optimizer", optimizer)) if v})
    if optimizer is not None and control["controller"] != "hcomc":
        raise _fail(
            f"option '--optimizer' = '{optimizer}' does not apply to controller "
            f"'{control['controller']}'; allowed: only with --controller hcomc"
        )
    return control


def _refuse_existing_file(path: Path, option: str, force: bool) -> None:
    """Stop before any work if the output file ``path`` that ``option`` names exists
    (unless --force) or is a directory."""
    if path.is_dir():
        raise _fail(f"option '{option}' = '{path}': is a directory; allowed: a file path")
    if path.exists() and not force:
        raise _fail(f"option '{option}' = '{path}': already exists; "
                    "allowed: a new file, or --force to overwrite it")  # fmt: skip


Force = Annotated[bool, typer.Option(help="Overwrite an existing output file.")]


def _refuse_overwrite(out_dir: Path | None, names: tuple[str, ...], force: bool) -> None:
    """Stop before a run if ``out_dir`` is a file or already holds a run (unless --force)."""
    if out_dir is None:
        return
    if out_dir.exists() and not out_dir.is_dir():
        raise _fail(f"option '--out' = '{out_dir}': exists and is not a directory")
    existing = [n for n in names if (out_dir / n).exists()]
    if existing and not force:
        raise _fail(
            f"option '--out' = '{out_dir}' already holds a run ({', '.join(existing)}); "
            "allowed: a new directory, or --force to overwrite it"
        )


Engine = Annotated[
    str, typer.Option(help="Simulation engine: hcomc, or sumo (SUMO co-simulation, hcomc[sumo]).")
]


def _engine(engine: str, config: ScenarioConfig | None = None) -> str:
    """Validate --engine (SUMO installed and able to run ``config`` when asked for)."""
    from hcomc.cli.sumo import engine_error

    problem = engine_error(engine, config)
    if problem is not None:
        raise _fail(problem)
    return engine


def _require_merge(cfg: ScenarioConfig, source: str, command: str) -> None:
    """Merge-controller commands need a merge scenario with ramp demand."""
    if cfg.scenario != "merge" or cfg.demand.ramp == "none":
        what = f"scenario = '{cfg.scenario}'" if cfg.scenario != "merge" else "demand.ramp = 'none'"
        raise _fail(
            f"no ramp vehicle entered the control zone: '{source}' has {what}, so '{command}' "
            "has no merge to control; allowed: a merge scenario with ramp demand (C1..C5, or "
            "scenario = 'merge' with demand.ramp = 'single' or 'flow'); use 'hcomc simulate' "
            "otherwise"
        )
