"""No result of hcomc takes a transcendental function from numpy.

numpy picks the code of its float64 ``exp``, ``log``, ``power``, ``tanh``, ``hypot``, ``cbrt``
… by the processor it runs on (e.g. SIMD versions for AVX-512, which differ from the C
library's in the last bit on many arguments), so a number computed with them can differ from
one machine to the next. The kernels take these functions from the C library (numba), and so
must Python code (``math``). This reads every module outside the figures and the import of
recorded field data (whose numbers are drawn, not reported) and fails on a call of such a
numpy function outside a compiled kernel. ``tests/scenario/test_fingerprints.py`` checks the
same on the runs themselves, with numpy's CPU dispatch disabled.
"""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "hcomc"
DISPATCHED = frozenset({
    "arccos", "arccosh", "arcsin", "arcsinh", "arctan", "arctan2", "arctanh", "cbrt", "cos",
    "cosh", "exp", "exp2", "expm1", "float_power", "hypot", "log", "log10", "log1p", "log2",
    "power", "sin", "sinh", "tan", "tanh",
})  # fmt: skip
"""numpy's float64 functions whose implementation depends on the CPU."""
EXEMPT = ("viz/", "sumo/highd.py")
"""Figures, and the conversion of recorded highD trajectories for plotting beside ours."""


def _kernel_lines(tree: ast.AST) -> set[int]:
    lines: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef) and any(
            "kernel" in ast.unparse(d) or "njit" in ast.unparse(d) for d in node.decorator_list
        ):
            lines.update(range(node.lineno, (node.end_lineno or node.lineno) + 1))
    return lines


def _dispatched_calls(path: Path, root: Path = SRC) -> list[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    compiled = _kernel_lines(tree)
    return [
        f"{path.relative_to(root)}:{node.lineno}: np.{node.func.attr}"
        for node in ast.walk(tree)
        if isinstance(node, ast.Call)
        and isinstance(node.func, ast.Attribute)
        and node.func.attr in DISPATCHED
        and ast.unparse(node.func.value) in {"np", "numpy"}
        and node.lineno not in compiled
    ]


def test_no_result_takes_a_cpu_dispatched_numpy_function() -> None:
    found = [
        call
        for path in sorted(SRC.rglob("*.py"))
        if not path.relative_to(SRC).as_posix().startswith(EXEMPT)
        for call in _dispatched_calls(path)
    ]
    assert found == []


def test_the_check_finds_a_call_outside_kernels_only(tmp_path: Path) -> None:
    module = tmp_path / "m.py"
    module.write_text(
        "import numpy as np\nfrom hcomc._jit import kernel\n\n"
        "@kernel\ndef k(x):\n    return np.exp(x)\n\n"
        "def f(x):\n    return np.power(x, 3.0) + np.sqrt(x)\n"
    )
    assert _dispatched_calls(module, tmp_path) == ["m.py:9: np.power"]
