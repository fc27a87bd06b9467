"""Every numeric input is bounded before anything large is allocated: extreme magnitudes
(1e-12, 1e9, 1e12, huge lists) are refused with one line naming the key, exit 2."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.config import ConfigError, load_config
from hcomc.config.loading import leaf_paths

runner = CliRunner()

EXTREME = [1e-12, 1e-6, 1e9, 1e12, 1e300, -1e9, math.inf, -math.inf, math.nan]


@pytest.mark.parametrize(
    ("key", "value", "fragment"),
    [
        ("dt", 1e-12, "greater than or equal to 0.001"),
        ("duration", 1e12, "less than or equal to 86400"),
        ("warmup", 1e9, "less than or equal to 3600"),
        ("log_interval", 1e-12, "multiple of dt"),
        ("demand.min_headway", 1e-12, "greater than or equal to 0.1"),
        ("platoon.followers", 10**9, "less than or equal to 100000"),
        ("road.length", 1e12, "less than or equal to 1000000"),
    ],
)
def test_extreme_values_are_refused_at_load(key, value, fragment):
    with pytest.raises(ConfigError) as error:
        load_config("C1", **{key: value})
    message = str(error.value)
    assert key.split(".")[-1] in message, message
    assert fragment in message, message
    assert "\n" not in message.strip()


def test_a_perception_history_beyond_the_memory_limit_is_refused_before_allocation():
    # 1 ms steps, 3 s delays and a day of dense demand: ~3,000 rows x ~1.7 M vehicles
    big = {"dt": 0.001, "log_interval": 1.0, "duration": 86_400, "warmup": 3600,
           "hdv.reaction_time_gap": 3.0, "demand.min_headway": 0.1,
           "demand.mean_headway_main_1": 0.11,
           "demand.mean_headway_main_2": 0.11}  # fmt: skip
    with pytest.raises(ConfigError, match="perception history of this run would need"):
        load_config("C1", **big)
    config = load_config("C1")
    # the estimate: (0.6 s / 0.1 s + 2) rows x 16 bytes x the expected vehicles
    expected = (30 + 90) * (1 / config.demand.mean_headway_main_1
                            + 1 / config.demand.mean_headway_main_2) + 1  # fmt: skip
    assert config.expected_vehicles() == pytest.approx(expected)
    assert config.history_gib() == pytest.approx(8 * 16 * expected / 2**30)


def test_a_long_platoon_profile_is_refused():
    profile = [[float(t), 20.0] for t in range(20_000)]
    with pytest.raises(ConfigError, match="profile"):
        load_config("platoon", **{"platoon.profile": profile})


@pytest.mark.parametrize(
    "args",
    [
        ["simulate", "C1", "--set", "dt=1e-12"],
        ["simulate", "C1", "--duration", "1e12"],
        ["simulate", "C1", "--set", "warmup=1e9"],
        ["simulate", "C1", "--set", "demand.min_headway=1e-12"],
        ["run", "C1", "--set", "dt=1e-12"],
        ["simulate", "corridor", "--set", "corridor.step_length=1e-12"],
        ["simulate", "corridor", "--duration", "1e12"],
        ["faults", "--seeds", "1000000000"],
    ],
)
def test_cli_extreme_values_one_line_exit_2(args):
    result = runner.invoke(app, args)
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output
    assert result.stderr.strip().count("\n") == 0, result.stderr


_FLOAT_KEYS = sorted(k for k, f in leaf_paths().items() if f.annotation is float)


@settings(max_examples=150, deadline=None)
@given(key=st.sampled_from(_FLOAT_KEYS), value=st.sampled_from(EXTREME))
def test_fuzz_extreme_magnitudes_are_refused_or_bounded(key, value):
    """Any float key at an extreme magnitude is either refused with a ConfigError naming
    it, or yields a config whose steps and perception history stay within bounds."""
    try:
        config = load_config("C1", **{key: value})
    except ConfigError as error:
        message = str(error)
    else:
        message = ""
    if message:
        assert key.split(".")[-1] in message
        return
    assert 1e-3 <= config.dt <= 1
    assert (config.warmup + config.duration) / config.dt <= 1e8
    assert config.history_gib() <= config.log_memory_limit
