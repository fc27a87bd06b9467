"""The library face: ``hcomc``'s own names are the objects of the modules that define them,
loaded on first use, so that ``import hcomc`` stays light; the documentation's examples import
from it alone; and ``hcomc.run`` / ``hcomc.compare`` give the command line's numbers."""

from __future__ import annotations

import ast
import importlib
import io
import json
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

import hcomc
from hcomc.cli import app
from hcomc.experiments.controller_arguments import configuration_labels

ROOT = Path(__file__).resolve().parents[2]
PYTHON_BLOCK = re.compile(r"^( *)```python\n(.*?)^\1```", re.S | re.M)
TIMING = ["wall_s", "decision_ms"]  # of each run's own timing, never the same twice
SMALL = {"duration": 40.0}  # long enough for the first ramp vehicle's merge, short to run


def test_every_exported_name_is_its_modules_object() -> None:
    names = set(hcomc.__all__) - {"__version__"}
    assert names == set(hcomc._HOMES)
    for name in sorted(names):
        home = importlib.import_module(hcomc._HOMES[name])
        assert getattr(hcomc, name) is getattr(home, name), name
    assert names <= set(dir(hcomc))


def test_an_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no attribute 'Simulator'"):
        hcomc.Simulator  # noqa: B018


def test_import_hcomc_loads_neither_numpy_nor_numba() -> None:
    code = "import sys, hcomc; print('numpy' in sys.modules, 'numba' in sys.modules)"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)  # fmt: skip
    assert done.stdout.split() == ["False", "False"]


BLOCK_EXTRA = """
import sys

class _NoGymnasium:
    def find_spec(self, name, path=None, target=None):
        if name.partition(".")[0] in ("gymnasium", "pettingzoo"):
            raise ModuleNotFoundError(f"No module named '{name}'", name=name)
        return None

sys.meta_path.insert(0, _NoGymnasium())
import hcomc
hcomc.Simulation, hcomc.run  # the rest of the face does not need the extra
try:
    from hcomc import MergeEnv
except ImportError as exc:
    print(exc)
"""


def test_a_name_of_a_missing_extra_says_which_extra_to_install_when_used() -> None:
    done = subprocess.run([sys.executable, "-c", BLOCK_EXTRA], capture_output=True, text=True,
                          check=True)  # fmt: skip
    assert "hcomc.MergeEnv needs the optional extra 'envs'" in done.stdout
    assert "pip install 'hcomc[envs]'" in done.stdout


def test_the_module_docstring_lists_every_name_and_the_type_checking_block_imports_it() -> None:
    """What the API reference renders statically (tests/test_api_reference.py checks the
    page): the face's list names every name, and the annotations' imports give each its
    object, from its home."""
    tree = ast.parse((ROOT / "src" / "hcomc" / "__init__.py").read_text(encoding="utf-8"))
    listed = set(re.findall(r":(?:func|class|data):`(\w+)`", ast.get_docstring(tree) or ""))
    assert set(hcomc._HOMES) <= listed, set(hcomc._HOMES) - listed
    (block,) = [n for n in tree.body if isinstance(n, ast.If)]  # if TYPE_CHECKING:
    imported = {
        alias.name: node.module
        for node in block.body
        if isinstance(node, ast.ImportFrom)
        for alias in node.names
    }
    assert set(imported) == set(hcomc._HOMES)
    for name, module in imported.items():  # from the home, or a package that re-exports it
        assert hcomc._HOMES[name].startswith(module or "?"), name


# --- the documentation's examples ------------------------------------------------------


def _python_blocks() -> list[tuple[str, str]]:
    """(where, code) of every Python block of the README and docs/*.md, and every script of
    examples/."""
    found = []
    for doc in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        text = doc.read_text(encoding="utf-8")
        for match in PYTHON_BLOCK.finditer(text):
            line = text.count("\n", 0, match.start()) + 1
            found.append((f"{doc.relative_to(ROOT)}:{line}", textwrap.dedent(match[2])))
    for script in sorted((ROOT / "examples").glob("*.py")):
        found.append((str(script.relative_to(ROOT)), script.read_text(encoding="utf-8")))
    return found


def _beside_the_face(tree: ast.AST) -> list[str]:
    """Every import from a module of hcomc, and every ``hcomc.<name>`` or ``from hcomc import
    <name>`` of a name the face does not have."""
    face = set(hcomc.__all__)
    bad = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            bad += [a.name for a in node.names if a.name.startswith("hcomc.")]
        elif isinstance(node, ast.ImportFrom) and node.module == "hcomc":
            bad += [f"from hcomc import {a.name}" for a in node.names if a.name not in face]
        elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("hcomc."):
            bad.append(f"from {node.module} import ...")
        elif isinstance(node, ast.Attribute) and getattr(node.value, "id", "") == "hcomc":
            bad += [] if node.attr in face else [f"hcomc.{node.attr}"]
    return bad


def test_every_documented_example_imports_from_the_top_level() -> None:
    blocks = _python_blocks()
    assert len(blocks) >= 25  # the guides' blocks and the example scripts were found
    bad = {where: found for where, code in blocks if (found := _beside_the_face(ast.parse(code)))}
    assert not bad, bad


def test_the_example_package_imports_what_the_face_has_from_the_face() -> None:
    """examples/my_controller uses documented helpers of hcomc.interface, hcomc.equations and
    hcomc.control beside the face, but nothing the face exports from elsewhere."""
    face = set(hcomc.__all__)
    bad = []
    for path in sorted((ROOT / "examples" / "my_controller").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("hcomc."):
                bad += [f"{path.name}: {a.name}" for a in node.names if a.name in face]
    assert not bad, bad


# --- hcomc.run and hcomc.compare --------------------------------------------------------


def test_run_gives_the_numbers_of_hcomc_run() -> None:
    command = ["run", "C1", "--controller", "fifo", "--seeds", "2", "--workers", "1",
               "--set", "duration=40", "--json"]  # fmt: skip
    result = CliRunner().invoke(app, command)
    assert result.exit_code == 0, result.output
    printed = pd.DataFrame(json.loads(result.stdout)).drop(columns=TIMING)
    runs = hcomc.run("C1", "fifo", seeds=2, overrides=SMALL).drop(columns=TIMING)
    assert list(runs["seed"]) == [0, 1]
    assert runs["merged"].all()
    assert runs["critical_distance"].notna().all()
    pd.testing.assert_frame_equal(runs, printed, check_dtype=False, rtol=1e-12)


def _as_csv(frame: pd.DataFrame) -> pd.DataFrame:
    """``frame`` as it reads back from a CSV file (empty text is NaN, as in the command's)."""
    return pd.read_csv(io.StringIO(frame.to_csv(index=False)))


def test_compare_gives_the_numbers_of_hcomc_compare(tmp_path: Path) -> None:
    command = ["compare", "--controllers", "fifo,hcomc", "--conditions", "C1", "--seeds", "2",
               "--workers", "1", "--set", "duration=40", "--out", str(tmp_path)]  # fmt: skip
    printed = CliRunner().invoke(app, command)
    assert printed.exit_code == 0, printed.output
    found = hcomc.compare(["fifo", "hcomc"], conditions=["C1"], seeds=2, overrides=SMALL)
    assert (found.suite, found.cells, found.seeds) == ("merge-v1", ("C1",), 2)
    assert found.configurations == ("FIFO", "HCOMC")
    assert found.comparisons == (("HCOMC", "FIFO"),)
    assert len(found.runs) == 4
    assert len(found.effects) == 5  # the paper's five metrics, one comparison, one cell
    assert found.effects["median_diff"].abs().sum() > 0  # the controllers differ
    for table in ("success", "success_pairs", "means", "effects", "safety"):
        written = pd.read_csv(tmp_path / f"{table}.csv")
        pd.testing.assert_frame_equal(_as_csv(getattr(found, table)), written, obj=table)
    written = pd.read_csv(tmp_path / "runs.csv")
    pd.testing.assert_frame_equal(_as_csv(found.runs[written.columns]), written, obj="runs")


@pytest.mark.parametrize(
    ("call", "fragment"),
    [
        (lambda: hcomc.compare(["fifo", "lifo"]), "'lifo': not a registered name; allowed:"),
        (lambda: hcomc.compare("fifo"), "argument 'controllers' = [fifo]: allowed: two or more"),
        (lambda: hcomc.compare(["fifo", "FIFO"]), "'FIFO' is given twice"),
        (lambda: hcomc.compare("fifo,game", conditions="C9"), "argument 'conditions': 'C9'"),
        (lambda: hcomc.compare("fifo,game", seeds=0), "argument 'seeds' = 0: allowed:"),
        (lambda: hcomc.compare("fifo,game", suite="merge-v0"), "argument 'suite' = 'merge-v0'"),
        (lambda: hcomc.compare("fifo,game", baseline="hcomc"), "'hcomc' is not among"),
        (lambda: hcomc.compare([object(), "fifo"]), "not a name or a class; allowed:"),
        (lambda: hcomc.run("C1", "lifo"), "'controller' (key 'control.controller' = 'lifo'"),
        (lambda: hcomc.run("C1", "fifo", optimizer="pso"), "'pso' does not apply to controller"),
        (lambda: hcomc.run("C1", "fifo", optimizer="tabu"), "key 'control.optimizer' = 'tabu'"),
        (lambda: hcomc.run("C1", engine="carla"), "argument 'engine' = 'carla': allowed: hcomc"),
        (lambda: hcomc.run("C1"), "control.controller = 'none'; allowed: a controller name"),
        (lambda: hcomc.run("platoon", "fifo"), "argument 'config' = 'platoon' has no merge"),
    ],
)  # fmt: skip
def test_bad_input_is_a_config_error_naming_it(call, fragment: str) -> None:
    with pytest.raises(hcomc.ConfigError) as raised:
        call()
    assert fragment in str(raised.value)


def test_a_controller_class_stands_for_the_module_or_file_that_defines_it(tmp_path) -> None:
    from hcomc.control.fifo import FIFOController
    from hcomc.control.registry import controller_class

    labels = configuration_labels([FIFOController, "hcomc"])
    assert labels == ["hcomc.control.fifo:FIFOController", "HCOMC"]
    source = tmp_path / "mine.py"
    source.write_text("class Mine:\n    def plan(self, view, group, rng):\n        pass\n")
    loaded = controller_class(f"{source}:Mine")  # as a run loads it
    assert configuration_labels(["fifo", loaded]) == ["FIFO", f"{source}:Mine"]

    class Local(FIFOController):
        pass

    with pytest.raises(hcomc.ConfigError, match="defined in the running script"):
        configuration_labels([Local, "fifo"])
