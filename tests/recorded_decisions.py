"""The recorded first planning instants of C1-C5 (``benchmarks/record_decisions.py``,
``benchmarks/data/decisions.pkl``), shared by the tests that score real merge problems."""

from __future__ import annotations

import os
import sys
from functools import cache
from pathlib import Path

from hcomc.config import ScenarioConfig
from hcomc.control.base import MergeGroup, TrafficView
from hcomc.control.hcomc.controller import HCOMCController
from hcomc.control.hcomc.problem import MergeProblem

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
Instant = tuple[str, ScenarioConfig, TrafficView, MergeGroup]


@cache
def recorded_instants() -> tuple[Instant, ...]:
    """The 60 recorded instants (``record_decisions.load_decisions``): name, config, view and
    key group of each."""
    sys.path.insert(0, str(BENCHMARKS))  # record_decisions imports its sibling throughput.py
    environ = dict(os.environ)  # the script pins its thread variables to 1 when imported
    try:
        from record_decisions import load_decisions
    finally:
        sys.path.remove(str(BENCHMARKS))
        # numba rereads NUMBA_NUM_THREADS at every compilation and refuses a change once its
        # threads run: the rest of the test session must see the variables it started with
        os.environ.clear()
        os.environ.update(environ)
    return tuple((d.name, d.config, d.view, d.group) for d in load_decisions())


def recorded_problem(index: int) -> MergeProblem:
    """A fresh merge problem of recorded instant ``index``, as the controller builds it."""
    _, config, view, group = recorded_instants()[index]
    return HCOMCController(config).problem(view, group)[0]
