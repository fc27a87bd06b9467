"""examples/train_ppo.py runs end to end: a short PPO training on hcomc/Merge-v0 and its
evaluation against FIFO, Game and HCOMC on the same seeds."""

from __future__ import annotations

import json
import runpy
import tempfile
from pathlib import Path

import pandas as pd
import pytest

pytest.importorskip("stable_baselines3")  # the rl extra (installed by the test extra)

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "train_ppo.py"


@pytest.mark.slow
def test_ppo_example_trains_and_compares(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    scratch = tmp_path / "temp"
    scratch.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(scratch))  # where SB3's default logger writes
    main = runpy.run_path(str(EXAMPLE))["main"]
    table = main(["--timesteps", "2048", "--envs", "2", "--eval-seeds", "2", "--out",
                  str(tmp_path)])  # fmt: skip
    assert list(table.index) == ["PPO", "FIFO", "Game", "HCOMC"]
    assert (table["episodes"] == 2).all()
    episodes = pd.read_csv(tmp_path / "episodes.csv")
    assert len(episodes) == 8
    assert set(episodes["seed"]) == {0, 1}
    merged = episodes[episodes["merged"]]
    assert len(merged) >= 6  # FIFO's VR waits at the lane end in seed 1: no merge to score
    assert merged["critical_distance"].notna().all()
    assert (tmp_path / "ppo_merge.zip").stat().st_size > 0
    run = json.loads((tmp_path / "run.json").read_text())
    assert run["timesteps"] == 2048
    assert run["train_seeds_from"] == 10_000
    assert (tmp_path / "comparison.md").read_text().startswith("| policy |")
    assert not list(scratch.glob("SB3-*"))  # a silent logger of its own: no folder left behind
