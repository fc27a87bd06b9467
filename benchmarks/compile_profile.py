"""Where a cold compile of hcomc's kernels spends its time.

Runs every compilation stage of ``hcomc.cli._compile`` in this process from an empty numba
cache (a temporary ``NUMBA_CACHE_DIR``) and records numba's compile events: each stage's
seconds, and each compiled function's exclusive seconds (its own typing, lowering and LLVM
optimisation, without the functions it compiles on the way). A function declared
``inline="always"`` is not compiled on its own where it is inlined: numba types and lowers its
body anew inside each caller, so that cost shows in the callers' time. ``--no-inline``
compiles the same kernels with numba's inlining off (LLVM may still inline), to measure what
the inlining costs at compile time; its run-time effect is measured by ``vs_sumo.py`` and
``decision_latency.py``.

    python benchmarks/compile_profile.py [--no-inline] [--top 25] [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from collections import defaultdict
from typing import Any


def _kernel_without_inline() -> None:
    """Make :func:`hcomc._jit.kernel` drop ``inline`` before any kernel module is imported."""
    import hcomc._jit

    original = hcomc._jit.kernel

    def kernel(function: Any = None, /, **options: Any) -> Any:
        options.pop("inline", None)
        return original(function, **options) if function is not None else original(**options)

    hcomc._jit.kernel = kernel  # type: ignore[assignment]


def profile(no_inline: bool) -> dict[str, Any]:
    from numba.core import event

    if no_inline:
        _kernel_without_inline()
    from hcomc.cli import _compile

    exclusive: dict[str, float] = defaultdict(float)
    count: dict[str, int] = defaultdict(int)
    stack: list[list[Any]] = []  # [name, start, children's seconds]

    class Timer(event.Listener):
        def on_start(self, ev: Any) -> None:
            dispatcher = ev.data["dispatcher"]
            name = f"{dispatcher.py_func.__module__}.{dispatcher.py_func.__qualname__}"
            stack.append([name, time.perf_counter(), 0.0])

        def on_end(self, ev: Any) -> None:
            name, start, children = stack.pop()
            inclusive = time.perf_counter() - start
            exclusive[name] += inclusive - children
            count[name] += 1
            if stack:
                stack[-1][2] += inclusive

    stages: dict[str, float] = {}
    with event.install_listener("numba:compile", Timer()):
        for key, (_, workload) in _compile.STAGES.items():
            began = time.perf_counter()
            workload()
            stages[key] = round(time.perf_counter() - began, 1)
    ranked = sorted(exclusive.items(), key=lambda item: -item[1])
    return {
        "no_inline": no_inline,
        "stages_s": stages,
        "total_s": round(sum(stages.values()), 1),
        "compiled_functions": len(exclusive),
        "compilations": sum(count.values()),
        "functions": [
            {"function": name, "seconds": round(seconds, 2), "compilations": count[name]}
            for name, seconds in ranked
        ],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--no-inline", action="store_true", help="numba's inlining off")
    parser.add_argument("--top", type=int, default=25, help="functions to list")
    parser.add_argument("--json", action="store_true", help="one JSON object")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="hcomc-numba-") as cache:
        os.environ["NUMBA_CACHE_DIR"] = cache  # before numba is imported
        result = profile(args.no_inline)
    result["functions"] = result["functions"][: args.top]
    if args.json:
        print(json.dumps(result, indent=1))
        return
    print(f"stages [s]: {result['stages_s']}  total {result['total_s']} s")
    print(f"{result['compiled_functions']} functions, {result['compilations']} compilations")
    for row in result["functions"]:
        print(f"{row['seconds']:8.2f} s  {row['compilations']:3d}x  {row['function']}")


if __name__ == "__main__":
    main()
