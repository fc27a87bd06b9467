"""The user documentation stands alone: every link, anchor and path it names exists in the
repository, it cites only the paper and published sources, and the key table is current."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from hcomc.config import ScenarioConfig, leaf_paths

ROOT = Path(__file__).resolve().parents[1]
DOCS = sorted(
    [ROOT / "README.md", ROOT / "benchmarks" / "RESULTS.md", *(ROOT / "docs").glob("*.md")]
)
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
REPO_PATH = re.compile(r"(?<![\w/.-])((?:src|docs|configs|tests|benchmarks|examples)/[\w./-]*)")
# material a user of the repository does not have
FORBIDDEN = re.compile(r"MODELS\.md|DESIGN|hcomc-paper\.md|\.\./shared|\bissues? \d|§")


def _slug(heading: str) -> str:
    """GitHub's anchor of a Markdown heading."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def _anchors(path: Path) -> set[str]:
    text = re.sub(r"```.*?```", "", path.read_text(encoding="utf-8"), flags=re.S)
    return {_slug(m) for m in re.findall(r"^#+\s+(.+)$", text, flags=re.M)}


def _prose(path: Path) -> str:
    """The text outside fenced code blocks (commands there are not references)."""
    return re.sub(r"```.*?```", "", path.read_text(encoding="utf-8"), flags=re.S)


def _names(path: Path) -> str:
    return str(path.relative_to(ROOT))


def test_slug_matches_github():
    assert _slug("Lane changes (Eq. 4–6 and Eq. 14)") == "lane-changes-eq-46-and-eq-14"
    assert _slug("Road (Section II-A)") == "road-section-ii-a"


@pytest.mark.parametrize("doc", DOCS, ids=_names)
def test_links_and_anchors_resolve(doc):
    missing = []
    for target in LINK.findall(_prose(doc)):
        if re.match(r"[a-z]+:", target):
            continue  # external URL
        file_part, _, anchor = target.partition("#")
        path = (doc.parent / file_part).resolve() if file_part else doc
        if not path.exists():
            missing.append(f"{target}: no such file")
        elif anchor and path.suffix == ".md" and anchor not in _anchors(path):
            missing.append(f"{target}: no section '#{anchor}'")
    assert not missing, f"{_names(doc)}: {missing}"


@pytest.mark.parametrize("doc", DOCS, ids=_names)
def test_repository_paths_named_anywhere_exist(doc):
    """Paths from the repository root (``src/...``, ``configs/...``), in prose or code blocks."""
    text = doc.read_text(encoding="utf-8")
    tokens = {t.rstrip(".,:;") for t in REPO_PATH.findall(text)}
    missing = sorted(
        t for t in tokens if not any(c in t for c in "*<>{}") and not (ROOT / t).exists()
    )
    assert not missing, f"{_names(doc)} names paths that do not exist: {missing}"


@pytest.mark.parametrize("doc", DOCS, ids=_names)
def test_cites_no_material_users_do_not_have(doc):
    hits = [
        f"line {i}: {line.strip()[:80]}"
        for i, line in enumerate(doc.read_text(encoding="utf-8").splitlines(), 1)
        if FORBIDDEN.search(line)
    ]
    assert not hits, f"{_names(doc)} cites internal material: {hits}"


def test_models_md_lists_every_config_key_with_its_current_default():
    text = (ROOT / "docs" / "models.md").read_text(encoding="utf-8")
    rows = dict(re.findall(r"^\| `([\w.]+)` \| `(.+?)` \|", text, flags=re.M))
    defaults = ScenarioConfig().model_dump(mode="json")
    assert set(rows) == set(leaf_paths())
    for key, shown in rows.items():
        value = defaults
        for part in key.split("."):
            value = value[part]
        assert json.loads(shown.replace("\\|", "|")) == value, key


CODE_FORBIDDEN = re.compile(
    r"MODELS(\.md)?\s*§|DESIGN(\.md)?\s*§|MODELS\.md|DESIGN\.md|STYLE\.md|hcomc-paper\.md"
    r"|\.\./shared|\(issues? \d"
)


CODE = [
    *(
        path
        for tree in ("src", "tests", "benchmarks", "examples")
        for path in (ROOT / tree).rglob("*.py")
    ),
    *(ROOT / "src" / "hcomc" / "configs").rglob("*.toml"),  # presets shipped with the package
    *(ROOT / "configs").rglob("*.toml"),  # example sweeps
]


def test_code_scan_covers_the_config_presets():
    names = {path.relative_to(ROOT).as_posix() for path in CODE}
    assert "src/hcomc/configs/conditions/C1.toml" in names
    assert "configs/sweeps/example.toml" in names


def test_code_cites_no_material_users_do_not_have():
    """Docstrings, comments and the TOML presets cite the paper and docs/, never internal
    design notes."""
    hits = [
        f"{path.relative_to(ROOT)}:{i}"
        for path in sorted(CODE)
        if path.name != "test_docs.py"
        for i, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
        if CODE_FORBIDDEN.search(line)
    ]
    assert not hits, hits
