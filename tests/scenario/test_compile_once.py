"""A fresh process loads the engine's compiled code from numba's cache instead of compiling it,
and the serial and parallel ensemble loops do not share a cache entry.

numba compiles some things anew in every process unless they are reached through cached
functions: a structref's default constructor (``StructRefProxy.__new__``, about 2.5 s for the
run state) and the Python-side methods of typed lists (about a second each). Every command,
worker process and environment would pay that before its first step. The run state and the
ensemble's lists are therefore built by cached functions; this test runs a simulation, an
ensemble and a vector environment in a fresh interpreter and asserts that numba's uncached
paths were never compiled there.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

_SCRIPT = textwrap.dedent(
    """
    import numpy as np
    from numba.typed import typedlist

    from hcomc.config import load_config
    from hcomc.sim.step.state import Core
    from hcomc.sim.engine import Simulation
    from hcomc.sim.ensemble import run_ensemble

    config = load_config("C1", duration=20)
    Simulation(config, seed=0).run()
    run_ensemble([Simulation(config, seed=s) for s in range(3)], threads=1)
    try:
        from hcomc.envs.vector import MergeVectorEnv
    except ImportError:  # the envs extra is optional
        pass
    else:
        envs = MergeVectorEnv(3, threads=1, scenario="C1")
        envs.reset(seed=0)
        for _ in range(3):
            envs.step(np.zeros((3, 2)))
    print("ctor", hasattr(Core, "_StructRefProxy__numba_ctor"))
    for name in ("_make_list", "_append", "_setitem", "_pop", "_length", "_getitem"):
        print(name, len(getattr(typedlist, name).overloads))
    """
)


@pytest.mark.slow
def test_fresh_process_compiles_no_structref_constructor_or_typed_list_method() -> None:
    done = subprocess.run(
        [sys.executable, "-c", _SCRIPT], capture_output=True, text=True, check=True, timeout=900
    )
    lines = dict(line.split() for line in done.stdout.splitlines())
    assert lines == {
        "ctor": "False",
        "_make_list": "0",
        "_append": "0",
        "_setitem": "0",
        "_pop": "0",
        "_length": "0",
        "_getitem": "0",
    }


def test_serial_and_parallel_ensemble_loops_have_their_own_cache_entries() -> None:
    # numba's cache keys an entry by function and signature, not by ``parallel``: a serial
    # loop compiled from the parallel one's code shared its entry, so whichever was compiled
    # first was loaded for both (the parallel ensemble then ran on one thread)
    from hcomc.sim.step import batch

    paths = {  # numba's cache index file of each function
        dispatcher._cache._cache_file._index_path  # type: ignore[attr-defined]
        for dispatcher in (batch.advance_batch, batch.advance_batch_serial)
    }
    assert len(paths) == 2
