"""The published numbers come from the code: the committed documentation agrees with the
committed run summary it was made from, and regenerating it from a (small, hand-made) results
directory writes exactly the documented files."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure
from PIL import Image
from typer.testing import CliRunner

import hcomc
from hcomc.cli import app
from hcomc.config import load_config
from hcomc.experiments import digest as digest_mod
from hcomc.experiments.claims import GROUPS, verdict_counts
from hcomc.experiments.narrative import values
from hcomc.experiments.paper import PAPER_METRICS
from hcomc.viz.gallery import GALLERY, read_stamp, record_scene
from hcomc.viz.publish import (
    GENERATED,
    PLACEHOLDER,
    README_END,
    README_START,
    image_stamp,
    readme_block,
    render_readme_block,
    render_reproduction,
    template,
    write_docs,
)

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
REVISION = "0123456789abcdef0123456789abcdef01234567"


def _verdicts(markdown: str) -> dict[tuple[str, str], tuple[str, str]]:
    """(claim, condition) -> (verdict, verdict (Holm)) of every claims table of a document."""
    rows: dict[tuple[str, str], tuple[str, str]] = {}
    header: list[str] | None = None
    for line in markdown.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if line.startswith("| claim | condition |"):
            header = cells
        elif header is not None and line.startswith("|---"):
            continue
        elif header is not None and line.startswith("| "):
            rec = dict(zip(header, cells, strict=True))
            key = (rec["claim"], rec["condition"])
            assert key not in rows, f"claim listed twice: {key}"
            rows[key] = (rec["verdict"], rec["verdict (Holm)"])
        else:
            header = None
    return rows


def _check_against_summary(doc: str, block: str, data: Path) -> None:
    """What test 4 asks of committed docs: verdicts, README numbers and the stamp."""
    summary = digest_mod.load(data)
    claims = summary.claims
    expected = {
        (r["claim"], r["condition"]): (r["verdict"], r["verdict_holm"])
        for _, r in claims.iterrows()
    }
    assert _verdicts(doc) == expected  # every claim, and every verdict as claims.csv has it
    assert doc == render_reproduction(summary)  # every number as the summary gives it
    assert block == render_readme_block(summary)
    paper = claims[claims["family"] == "paper"]  # every other family is counted apart
    counts = {c: verdict_counts(paper, c).loc["all"] for c in ("verdict", "verdict_holm")}

    def verdicts(c: pd.Series) -> str:  # "1 holds, 1 is reversed", "2 hold, 2 are reversed"
        hold = "holds" if c["holds"] == 1 else "hold"
        are = "is" if c["reversed"] == 1 else "are"
        return f"{c['holds']} {hold}, {c['reversed']} {are} reversed and {c['undecided']} undecided"

    assert f"Of the\n{len(paper)} claims, {verdicts(counts['verdict'])}" in block
    assert verdicts(counts["verdict_holm"]) in block
    prov = summary.provenance
    assert f"(hcomc {prov.version}, git revision" in block
    assert f"from the run `{prov.command}` (hcomc {prov.version}, git revision" in doc


# --------------------------------------------------------------------------- committed docs
def test_committed_docs_match_their_summary() -> None:
    doc = (DOCS / "reproduction.md").read_text(encoding="utf-8")
    block = readme_block((ROOT / "README.md").read_text(encoding="utf-8"))
    assert doc.startswith(GENERATED)
    _check_against_summary(doc, block, DOCS / "data")


def test_committed_docs_are_stamped_with_this_version() -> None:
    prov = digest_mod.load(DOCS / "data").provenance
    assert prov.version == hcomc.__version__
    stamp = image_stamp(prov.version, prov.revision)
    for name in GALLERY:
        assert read_stamp(DOCS / "img" / name) == stamp, name


# --------------------------------------------------------------------------- templates
REFERENCE = re.compile(
    r"C[1-5]|Eqs?\. \d+(?:–\d+)?|Fig\. \d|Table I{1,3}|Section I{0,3}V?-?[A-D]?|\bII\b|"
    r"m²|m/s²|lane-2|lane 2|(?<![\d.])0(?![\d.])"  # zero, the reference of a difference
)


@pytest.mark.parametrize("name", ["reproduction.md", "readme.md"])
def test_template_text_has_no_numbers_of_its_own(name: str) -> None:
    """Outside placeholders, comments and references (C1, Eq. 15, Table II, Fig. 2, a
    difference's 0), the templates hold no digit: every number of the documents is
    computed."""
    text = re.sub(r"<!--.*?-->", "", template(name), flags=re.S)
    text = PLACEHOLDER.sub("", text)
    text = REFERENCE.sub("", text)
    text = re.sub(r"`[^`]*`", "", text)  # commands and paths
    text = re.sub(r"\]\([^)]*\)", "]", text)  # link targets
    assert re.findall(r".{0,30}\d.{0,30}", text) == []


# --------------------------------------------------------------------------- regeneration
CONFIGURATIONS = (
    "FIFO", "Game", "HCOMC", "HCOMC-PSO", "HCOMC-SA", "FIFO-R", "Game-R", "HCOMC-R", "HCOMC+",
)  # fmt: skip


def _runs(seeds: int) -> pd.DataFrame:
    """Hand-made runs: every condition and configuration over ``seeds`` seeds; HCOMC's critical
    distance 10 m above FIFO's in every seed, its fuel equal; HCOMC cooperates laterally in
    C2; one Game run without a critical distance; HCOMC fails to merge in seed 1 of C3; Game
    cooperates longitudinally in odd seeds; HCOMC's last plan switches in seed 3."""
    rng = np.random.default_rng(11)
    rows = []
    for cond in ("C1", "C2", "C3", "C4", "C5"):
        for conf in CONFIGURATIONS:
            hcomc_like = conf.startswith("HCOMC")
            for seed in range(seeds):
                rec = {
                    "condition": cond, "configuration": conf, "seed": seed,
                    "mode": ("lateral" if cond == "C2" else "longitudinal") if hcomc_like
                    else "longitudinal" if conf == "Game" and seed % 2 else "none",
                    "plan_switches": seed % 2 if hcomc_like else 0,
                    "final_switch": hcomc_like and seed == 3,
                    "sequence": "behind" if seed % 3 else "ahead",
                    "eq19_branch": "gate" if hcomc_like else "", "replans": seed % 4,
                    "fallback": False, "decision_ms": 5.0, "vmc_kind": "CAV", "collisions": 0,
                    "merged": (cond, conf, seed) != ("C3", "HCOMC", 1),
                }  # fmt: skip
                rec.update({m: float(rng.uniform(1.0, 2.0)) for m in PAPER_METRICS})
                rec["critical_distance"] = 50.0 + seed + (10.0 if conf == "HCOMC" else 0.0)
                rec["fuel"] = 3.0
                if (cond, conf, seed) == ("C1", "Game", 2):
                    rec["critical_distance"] = np.nan
                rows.append(rec)
    return pd.DataFrame(rows)


def _results(root: Path, seeds: int = 8, versions: tuple[str, ...] = ("",)) -> Path:
    runs = _runs(seeds)
    root.mkdir(parents=True)
    runs.to_parquet(root / "runs.parquet", index=False)
    runs[runs["seed"] == 0].to_csv(root / "paper_scenario.csv", index=False)
    (root / "manifests").mkdir()
    for i, cond in enumerate(("C1", "C2", "C3", "C4", "C5")):
        manifest = {
            "config": load_config(cond).model_dump(mode="json"),
            "hcomc_version": hcomc.__version__ + versions[i % len(versions)],
            "git_revision": REVISION,
        }
        (root / "manifests" / f"{cond}-FIFO-seed0.json").write_text(json.dumps(manifest))
    command = f"hcomc reproduce --seeds {seeds} --out results"
    (root / digest_mod.RUN_RECORD).write_text(json.dumps({"command": command}))
    return root


README = f"""# project

Intro text that stays.

{README_START}
old numbers
{README_END}

Text after the block that stays.
"""


@pytest.fixture(scope="module")
def scene(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A recorded scene of a short C2 run (40 s, its merge near 27 s), simulated once."""
    root = tmp_path_factory.mktemp("scene")
    png = record_scene(root, "C2", 1, {"duration": 40.0})
    assert png.startswith(b"\x89PNG")
    return root / "scene"


def _with_scene(results: Path, scene: Path) -> Path:
    import shutil

    shutil.copytree(scene, results / "scene")
    return results


@pytest.fixture(scope="module")
def published(
    tmp_path_factory: pytest.TempPathFactory, scene: Path
) -> tuple[Path, Path, Path, list[Path]]:
    root = tmp_path_factory.mktemp("published")
    results = _with_scene(_results(root / "results"), scene)
    readme = root / "README.md"
    readme.write_text(README, encoding="utf-8")
    written = write_docs(results, root / "docs", readme=readme)
    return results, root / "docs", readme, written


def test_regeneration_writes_exactly_the_documented_files(
    published: tuple[Path, Path, Path, list[Path]],
) -> None:
    _, docs, readme, written = published
    expected = {
        docs / "reproduction.md",
        readme,
        *(docs / "data" / name for name in digest_mod.DATA_FILES),
        *(docs / "img" / name for name in GALLERY),
    }
    assert set(written) == expected
    on_disk = {p for p in docs.rglob("*") if p.is_file()}
    assert on_disk == expected - {readme}  # nothing else, no temporary file left
    text = readme.read_text(encoding="utf-8")
    assert text.startswith("# project\n\nIntro text that stays.\n\n")
    assert text.endswith("\n\nText after the block that stays.\n")
    assert "old numbers" not in text


def test_regenerated_docs_match_their_summary(
    published: tuple[Path, Path, Path, list[Path]],
) -> None:
    _, docs, readme, _ = published
    doc = (docs / "reproduction.md").read_text(encoding="utf-8")
    block = readme_block(readme.read_text(encoding="utf-8"))
    _check_against_summary(doc, block, docs / "data")
    summary = digest_mod.load(docs / "data")
    rows = summary.claims.set_index(["claim", "condition"])
    cd = rows.loc[("HCOMC critical distance higher than FIFO", "C1")]
    assert (cd["median_diff"], cd["holds"], cd["n"]) == (10.0, 8, 8)
    assert (cd["verdict"], cd["verdict_holm"]) == ("holds", "undecided")  # 8 seeds: p > m/2^8
    assert "| HCOMC critical distance higher than FIFO | C1 | 10 [10, 10] | holds |" in doc
    assert summary.provenance.command == "hcomc reproduce --seeds 8 --out results"
    assert summary.provenance.seeds == 8
    assert summary.provenance.settings["cav_penetration"]["C5"] == 0.3
    # Table III: each row over its own seeds (Game lacks seed 2 of C1, the others have all 8)
    t3 = summary.tables[(summary.tables["table"] == "III") & (summary.tables["condition"] == "C1")]
    t3 = t3.set_index("configuration")
    assert t3.loc["Game", "critical_distance_n"] == 7
    assert t3.loc["HCOMC", "critical_distance_n"] == 8
    assert t3.loc["HCOMC", "critical_distance"] == pytest.approx(
        np.mean([60.0 + s for s in range(8)])
    )
    c3 = summary.decisions.set_index(["condition", "configuration"]).loc[("C3", "HCOMC")]
    assert (c3["merged"], c3["runs"]) == (7, 8)
    assert "| C3 | NSGA-II | 7/8 |" in doc
    assert "VR merged in 39 of 40 runs" in block
    game = "| Game's VMC cooperates longitudinally in ≥ 50 % of C2 runs (Section IV-A) |"
    assert f"{game} 50 % (4 of 8) | met |" in doc
    switch = "| HCOMC-R last plan switches the commanded vehicle in ≤ 5 % of runs |"
    assert f"{switch} 12 % (5 of 40) | **not met** |" in doc
    assert "| HCOMC (plans once, as published) merges in ≥ 99 % of runs | 98 % (39 of 40) |" in doc
    ext = summary.claims[summary.claims["group"] == GROUPS["extension"]]
    assert len(ext) == len(summary.claims[summary.claims["group"] == GROUPS["table3"]])
    assert "| HCOMC+ critical distance higher than FIFO | C1 |" in doc


def test_regenerated_images_are_stamped(published: tuple[Path, Path, Path, list[Path]]) -> None:
    _, docs, _, _ = published
    stamp = f"hcomc {hcomc.__version__} · {REVISION[:12]}"
    assert image_stamp(hcomc.__version__, REVISION) == stamp
    assert image_stamp("1.0", REVISION + "-dirty") == f"hcomc 1.0 · {REVISION[:12]}-dirty"
    for name in GALLERY:
        with Image.open(docs / "img" / name) as im:
            assert im.format == ("GIF" if name.endswith(".gif") else "PNG")
            assert im.size[0] > 600
            if im.format == "GIF":
                assert im.n_frames > 10
        assert read_stamp(docs / "img" / name) == stamp, name


def test_the_stamp_is_drawn_in_the_bottom_right_corner(tmp_path: Path) -> None:
    from hcomc.viz.gallery import _save_png

    def figure() -> Figure:
        fig = Figure(figsize=(4, 3))
        fig.add_subplot().plot([0, 1], [0, 1])
        return fig

    plain = tmp_path / "plain.png"
    figure().savefig(plain, format="png", dpi=150)
    stamped = _save_png(figure(), tmp_path / "stamped.png", "hcomc 9.9 · abc")
    a = np.asarray(Image.open(plain).convert("L"), dtype=float)
    b = np.asarray(Image.open(stamped).convert("L"), dtype=float)
    rows, cols = np.nonzero(np.abs(a - b) > 0)
    assert rows.size > 20  # the text is there
    assert rows.min() > 0.9 * a.shape[0]
    assert cols.min() > 0.6 * a.shape[1]  # and only there
    assert read_stamp(stamped) == "hcomc 9.9 · abc"


def test_the_summary_reads_back_exactly(published: tuple[Path, Path, Path, list[Path]]) -> None:
    results, docs, _, _ = published
    fresh, saved = digest_mod.digest(results), digest_mod.load(docs / "data")
    assert saved.provenance == fresh.provenance
    for name in ("claims", "tables", "decisions", "scenario"):
        pd.testing.assert_frame_equal(
            getattr(saved, name), getattr(fresh, name), check_dtype=False, check_exact=True
        )


def test_regeneration_is_reproducible(
    published: tuple[Path, Path, Path, list[Path]], tmp_path: Path
) -> None:
    results, docs, _, _ = published
    again = tmp_path / "docs"
    write_docs(results, again)
    for name in ("reproduction.md", *(f"data/{n}" for n in digest_mod.DATA_FILES)):
        assert (again / name).read_bytes() == (docs / name).read_bytes(), name


def test_the_narrative_values_cover_the_templates(
    published: tuple[Path, Path, Path, list[Path]],
) -> None:
    _, docs, _, _ = published
    named = values(digest_mod.load(docs / "data"))
    for name in ("reproduction.md", "readme.md"):
        assert set(PLACEHOLDER.findall(template(name))) <= set(named)


def test_refuses_what_it_did_not_write(scene: Path, tmp_path: Path) -> None:
    results = _with_scene(_results(tmp_path / "results", seeds=3), scene)
    docs = tmp_path / "docs"
    docs.mkdir()
    (docs / "reproduction.md").write_text("# A document written by hand\n", encoding="utf-8")
    with pytest.raises(ValueError, match="not written by hcomc docs"):
        write_docs(results, docs)
    assert sorted(p.name for p in docs.iterdir()) == ["reproduction.md"]
    readme = tmp_path / "README.md"
    readme.write_text("# no block here\n", encoding="utf-8")
    with pytest.raises(ValueError, match="exactly one block"):
        write_docs(results, tmp_path / "other", readme=readme)
    assert not (tmp_path / "other").exists()
    written = write_docs(results, docs, force=True)  # --force replaces it
    assert (docs / "reproduction.md").read_text(encoding="utf-8").startswith(GENERATED)
    assert docs / "reproduction.md" in written


def test_refuses_results_of_several_versions(tmp_path: Path) -> None:
    results = _results(tmp_path / "results", seeds=3, versions=("", "+other"))
    with pytest.raises(ValueError, match="mixes runs of 2 code versions"):
        digest_mod.digest(results)


def test_docs_command(scene: Path, tmp_path: Path) -> None:
    results = _with_scene(_results(tmp_path / "results", seeds=3), scene)
    readme = tmp_path / "README.md"
    readme.write_text(README, encoding="utf-8")
    args = ["docs", str(results), "--out", str(tmp_path / "docs"), "--readme", str(readme)]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert "reproduction.md" in result.stdout
    assert "old numbers" not in readme.read_text(encoding="utf-8")
    bad = CliRunner().invoke(app, ["docs", str(tmp_path / "nothing"), "--out", str(tmp_path)])
    assert bad.exit_code == 2
    assert "does not exist" in bad.stderr
    assert "Traceback" not in bad.output
