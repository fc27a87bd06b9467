"""The documentation site builds without a warning (``mkdocs build --strict``, as CI does),
its API reference renders the objects users use, and every public package has a page.

The build reads hcomc's sources statically: it needs neither the compiled kernels nor an
import of hcomc (a test below proves it by blocking the import)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "hcomc"
REFERENCE = ROOT / "docs" / "reference"

# Public parts of hcomc without a reference page, and why.
UNDOCUMENTED = {
    "cli": "the command line; `hcomc --help` documents it",
    "rng": "one helper, how a run derives its generator from its seed",
}

# Names each page must render (their anchors: the object is documented, not just named).
RENDERED = {
    "config": ["hcomc.config.load_config", "hcomc.config.ScenarioConfig"],
    "interface": ["hcomc.interface.MergePlan", "hcomc.interface.TrafficView"],
    "control": ["hcomc.control.registry.make_controller", "hcomc.control.validation.check_plan"],
    "sim": ["hcomc.sim.engine.Simulation", "hcomc.sim.log.SimulationLog"],
    "metrics": ["hcomc.metrics.compute_metrics"],
    "equations": [
        "hcomc.equations.idm.idm_acceleration",
        "hcomc.equations.car_following.follow_acceleration",
        "hcomc.equations.selection.select_eq19",
    ],
}

# Blocks every import of hcomc in the build's interpreter (a sitecustomize module).
BLOCK_IMPORT = """
import sys

class _BlockHcomc:
    def find_spec(self, name, path=None, target=None):
        if name == "hcomc" or name.startswith("hcomc."):
            raise ImportError(f"the documentation build imported {name}")
        return None

sys.meta_path.insert(0, _BlockHcomc())
"""


@pytest.fixture(scope="module")
def build(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """The site, built once into a temporary directory, and mkdocs' log."""
    tmp = tmp_path_factory.mktemp("mkdocs")
    (tmp / "sitecustomize.py").write_text(BLOCK_IMPORT, encoding="utf-8")
    env = {**os.environ, "PYTHONPATH": str(tmp), "PYTHONDONTWRITEBYTECODE": "1"}
    site = tmp / "site"
    had_site = (ROOT / "site").exists()
    result = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(site)],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=300, check=False,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr[-5000:]
    assert (ROOT / "site").exists() == had_site, "mkdocs wrote into the repository"
    return site, result.stderr


def _html(site: Path, page: str) -> str:
    return (site / "reference" / page / "index.html").read_text(encoding="utf-8")


def _public_packages() -> set[str]:
    """Every subpackage and module of hcomc whose name does not start with an underscore."""
    names = {p.name for p in PACKAGE.iterdir() if p.is_dir() and (p / "__init__.py").exists()}
    names |= {p.stem for p in PACKAGE.glob("*.py")}
    return {n for n in names if not n.startswith("_")}


def test_build_is_strict_clean_and_never_imports_hcomc(build):
    _, log = build
    assert "WARNING" not in log
    assert "Documentation built" in log


def test_only_links_out_of_docs_are_left_unresolved(build):
    """mkdocs reports links it did not find at "info" (mkdocs.yml): each must be a link from
    a page to a file outside docs/, which the site does not hold, never one between pages."""
    _, log = build
    unresolved = re.findall(r"Doc file '([^']+)' contains a link '([^']+)', but the target", log)
    unresolved += re.findall(
        r"Doc file '([^']+)' contains an unrecognized relative link '([^']+)'", log
    )
    docs = (ROOT / "docs").resolve()
    inside = []
    for page, link in unresolved:
        target = (docs / page).parent / link.partition("#")[0]
        if target.resolve().is_relative_to(docs) and not target.is_dir():
            inside.append(f"{page}: {link}")
    assert not inside, inside


def test_reference_pages_render_the_objects_users_use(build):
    site, _ = build
    for page, names in RENDERED.items():
        html = _html(site, page)
        missing = [name for name in names if f'id="{name}"' not in html]
        assert not missing, f"reference/{page}: {missing} not rendered"
    assert "MergePlan" in _html(site, "control")


def test_the_library_face_is_rendered_name_by_name(build):
    """Every name ``hcomc`` exports (its ``__all__``, read from the source like the build)
    has its entry on reference/hcomc."""
    import ast

    tree = ast.parse((PACKAGE / "__init__.py").read_text(encoding="utf-8"))
    (names,) = [
        ast.literal_eval(node.value)
        for node in tree.body
        if isinstance(node, ast.Assign) and getattr(node.targets[0], "id", "") == "__all__"
    ]
    html = _html(build[0], "hcomc")
    missing = [n for n in names if n != "__version__" and f'id="hcomc.{n}"' not in html]
    assert not missing, missing


def test_docstring_cross_references_become_links(build):
    """``:func:`load_config``` in a docstring is a link on the site, not the role's text."""
    site, _ = build
    html = _html(site, "config")
    assert ":func:" not in html
    assert ":class:" not in html
    assert 'href="#hcomc.config.load_config"' in html


def test_every_public_package_has_a_reference_page():
    """A new public package fails this until it has docs/reference/<name>.md, in the nav,
    documenting ``hcomc.<name>`` (or is listed in UNDOCUMENTED, with the reason)."""
    pages = {p.stem for p in REFERENCE.glob("*.md")}
    expected = (_public_packages() - set(UNDOCUMENTED)) | {"hcomc"}  # and the library face
    assert pages == expected, f"missing pages: {expected - pages}; extra: {pages - expected}"
    nav = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    for name in sorted(pages - {"hcomc"}):
        assert f"hcomc.{name}: reference/{name}.md" in nav, name
        text = (REFERENCE / f"{name}.md").read_text(encoding="utf-8")
        assert re.search(rf"^::: hcomc\.{name}$", text, flags=re.M), name
    assert "- hcomc: reference/hcomc.md" in nav
    assert re.search(r"^::: hcomc$", (REFERENCE / "hcomc.md").read_text(encoding="utf-8"), re.M)
