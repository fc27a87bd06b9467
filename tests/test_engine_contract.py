"""The engine contract (:func:`hcomc.sim.contract.check_engine`) on our engine and on the SUMO
co-simulation, engines that break it, and batching as a capability of an engine class
(:func:`hcomc.interface.run_all`) instead of a test of its type."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from hcomc import Simulation, StepListener, load_config, run_ensemble
from hcomc.interface import run_all
from hcomc.sim.contract import check_engine


def _scenario(controller: str = "fifo") -> Any:
    return load_config("C2", duration=30.0, control={"controller": controller})


@pytest.mark.parametrize("controller", ["fifo", "hcomc"])
def test_our_engine_keeps_the_contract(controller):
    check_engine(Simulation, _scenario(controller))


def test_the_sumo_cosimulation_keeps_the_contract():
    pytest.importorskip("libsumo")
    from hcomc.sumo.cosim import SumoSimulation

    check_engine(SumoSimulation, _scenario())


class _Silent(Simulation):
    """Reports no progress."""

    def run(self, progress: Callable[[int, int], None] | None = None) -> Any:
        return super().run(None)


class _Forgetful(Simulation):
    """Returns something else than its log."""

    def run(self, progress: Callable[[int, int], None] | None = None) -> Any:
        super().run(progress)
        return None


class _Unasked(Simulation):
    """Forgets what its decisions were asked."""

    @property
    def requests(self) -> Any:
        return []

    @requests.setter
    def requests(self, value: Any) -> None:
        pass


class _Mislabelled(Simulation):
    """Writes another seed into its log."""

    def run(self, progress: Callable[[int, int], None] | None = None) -> Any:
        log = super().run(progress)
        log.meta["seed"] = self.seed + 100
        return log


class _Unattached(Simulation):
    """Keeps the listeners it is given without attaching them."""

    def __init__(self, *args: Any, listeners: Any = (), **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.listeners = tuple(listeners)


class _Deaf(Simulation):
    """Attaches its listeners but never calls them."""

    def run(self, progress: Callable[[int, int], None] | None = None) -> Any:
        listeners, self.listeners = self.listeners, ()
        try:
            return super().run(progress)
        finally:
            self.listeners = listeners


def _shifted(config, seed, ctl, **listeners):
    return Simulation(config, seed + 1, ctl, **listeners)  # runs another seed than it says


def _frozen(config, seed, ctl, **listeners):
    return Simulation(config, 3, ctl, **listeners)  # every seed the same traffic


@pytest.mark.parametrize(
    ("make", "broken"),
    [
        (_Silent, "run reports its progress"),
        (_Forgetful, "run returns the engine's log"),
        (_shifted, "the engine's seed is 4, made with 3"),
        (lambda config, seed, ctl, **_: Simulation(config, seed), "keeps the controller"),
        (_frozen, "another seed gives the same traffic"),
        (_Unasked, "each decision has the request it answered"),
        (_Mislabelled, "the log records seed 103"),
        (_Unattached, "each listener is attached once"),
        (_Deaf, "before_step was called at steps"),
    ],
)
def test_an_engine_that_breaks_a_promise_fails_naming_it(make, broken):
    with pytest.raises(AssertionError, match=broken):
        check_engine(make, _scenario())


class _Batched(Simulation):
    """Runs its kind as one batch, and counts the batches."""

    batches: list[int] = []  # noqa: RUF012  (a class-level record the test reads)

    @classmethod
    def run_together(cls, sims: Any, *, threads: int | None = None) -> None:
        cls.batches.append(len(sims))
        super().run_together(sims, threads=threads)


class _Stepwise(Simulation):
    """Changes how a run advances: must not be batched by its parent's run_together."""

    runs = 0

    def run(self, progress: Callable[[int, int], None] | None = None) -> Any:
        type(self).runs += 1
        return super().run(progress)


def test_run_all_batches_a_class_that_defines_run_together_and_runs_others_alone():
    config = load_config("C1", duration=10.0)
    batched = [_Batched(config, seed) for seed in (1, 2, 3)]
    stepwise = [_Stepwise(config, seed) for seed in (1, 2)]
    plain = Simulation(config, 1)
    run_all([batched[0], *stepwise, *batched[1:], plain])
    assert _Batched.batches == [3]  # one batch of its three runs
    assert _Stepwise.runs == 2  # the subclass of Simulation ran alone, each run
    for sim in (*batched, *stepwise, plain):
        assert sim.finished
    alone = Simulation(config, 2)
    alone.run()
    assert np.array_equal(alone.log.x, batched[1].log.x, equal_nan=True)  # batched = alone


class _Counting(StepListener):
    """Counts the steps it was called before."""

    def __init__(self) -> None:
        self.steps = 0

    def before_step(self, run: Any, t: float) -> None:
        self.steps += 1


def test_a_run_with_listeners_runs_alone_in_a_batch():
    config = load_config("C1", duration=10.0)
    counting = _Counting()
    listened, plain = Simulation(config, 1, listeners=[counting]), Simulation(config, 1)
    run_all([listened, plain])
    assert listened.finished
    assert plain.finished
    assert counting.steps == listened.n_steps  # its listener acted before every step
    assert np.array_equal(listened.log.x, plain.log.x, equal_nan=True)  # and only watched
    with pytest.raises(ValueError, match="advances alone"):
        run_ensemble([Simulation(config, 2, listeners=[StepListener()])])
