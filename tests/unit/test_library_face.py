"""The library face: ``hcomc``'s own names are the objects of the modules that define them,
loaded on first use, so that ``import hcomc`` stays light."""

from __future__ import annotations

import importlib
import subprocess
import sys

import pytest

import hcomc


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
