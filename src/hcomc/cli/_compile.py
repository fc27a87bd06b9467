"""Compile the kernels a command needs before it runs, and say so (:func:`ensure_compiled`).

A command names the stages it uses (:data:`STAGES`: the engines' of :mod:`hcomc.sim.stages`,
the batches', the learning environments'); :func:`hcomc._compiling.ensure` compiles the
missing ones with a line per stage, running their tiny real workloads in one spawned process
(compiling leaves some 3 GB in a process, loading the cache 0.3 GB); the command then loads
them. How a stage is known to be compiled, and how concurrent processes share one
compilation: :mod:`hcomc._compiling`.
"""

from __future__ import annotations

from typing import Any

from hcomc._compiling import Stage, cache_directory, ensure, marker_path
from hcomc.sim.stages import SCENARIO as ENGINE_SCENARIO
from hcomc.sim.stages import STAGES as ENGINE_STAGES

__all__ = ["IN_CHILD", "SCENARIO", "STAGES", "cache_directory", "ensure_compiled", "marker_path"]


def batches() -> None:
    """Batches as ``run``, ``sweep`` and ``reproduce`` run them (ensemble on one thread in a
    worker, on all with ``--workers 1``; undisturbed runs; metrics)."""
    import numba

    from hcomc.experiments.runner import ALL_CONFIGURATIONS, RunSpec, run_batch

    specs = [RunSpec("C2", label, 0, {"duration": 40.0}) for label in ALL_CONFIGURATIONS]
    run_batch(specs, threads=1)
    if int(numba.config.NUMBA_NUM_THREADS) > 1:  # type: ignore[attr-defined]
        run_batch(specs[:2], threads=2)  # the parallel kernel


def environments() -> None:
    """A few steps of the learning environments, single and vector (needs the ``envs``
    extra). An environment compiles the engine's stages itself, with lines on stderr
    (:func:`hcomc.sim.stages.ensure_kernels`); its own kernels take seconds."""
    try:
        import gymnasium
    except ImportError:
        return
    import hcomc.envs  # noqa: F401  (registers the environments)
    from hcomc.envs.vector import MergeVectorEnv

    env = gymnasium.make("hcomc/Merge-v0")
    env.reset(seed=0)
    env.step(env.action_space.sample())
    env.close()
    vector = MergeVectorEnv(2)
    vector.reset(seed=0)
    vector.step(vector.action_space.sample())
    vector.close()


STAGES: dict[str, Stage] = {
    **ENGINE_STAGES,
    "batches": Stage("ensemble runs and metrics", batches, 28.0),
    "envs": Stage("learning environments", environments, 6.0),
}
"""Together they compile every kernel of the commands and the environments (measured: their
processes compile nothing afterwards)."""

SCENARIO = (*ENGINE_SCENARIO, "batches")
"""The stages of a command that runs the paper's scenarios (``simulate``, ``plan``, ``run``,
``compare``, ``sweep``, ``reproduce``, ``faults``)."""

IN_CHILD = True
"""Run the stages in a spawned process (False: in this one, as the tests' fakes do)."""


def ensure_compiled(console: Any, stages: tuple[str, ...] = SCENARIO) -> None:
    """Compile the kernels of ``stages`` (keys of :data:`STAGES`) unless this environment's
    cache holds them for the current sources, with a line per stage on ``console`` (a rich
    Console); silent when it does."""

    def say(text: str, end: str = "\n") -> None:
        console.print(text, end=end, markup=False, highlight=False, soft_wrap=True)
        console.file.flush()

    ensure(cache_directory(), STAGES, stages, say, in_child=IN_CHILD)
