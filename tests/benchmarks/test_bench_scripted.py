"""The scripted cell's benchmark: config, one real episode, totals and the bench table rows."""

from __future__ import annotations

import pytest

from benchmarks.figures import scripted_figures
from benchmarks.scripted import (
    Episode,
    Scenario,
    ScriptedBenchConfig,
    close_envs,
    play,
    summarise,
)
from configs import ConfigError, load_config
from envs.tasks import get_task


def test_bundled_config_has_the_issue_targets():
    cfg = load_config(ScriptedBenchConfig, "bench_scripted")
    assert cfg.seeds == (0, 20)
    by = {s.name: s for s in cfg.scenarios}
    assert by["paper_mixed, static belt"].min_correct == 1.0
    assert by["paper_mixed, static belt"].min_tiles_per_min == 24.0
    moving = by["paper_mixed, belt 0.1 m/s"]
    assert moving.min_correct == 0.98
    stream = get_task("MosaicStream-v1").env
    for name in ("paper_mixed, belt 0.1 m/s", "paper_mixed, belt 0.1 m/s, realistic camera"):
        env = by[name].env_kwargs()  # the task's belt and stream: two tiles at reset
        assert env["belt_speed"] == 0.1 and env["feed"] == "stream"
        assert env["stream_initial"] == stream["stream_initial"] == 2
    with pytest.raises(ConfigError, match="seeds"):
        ScriptedBenchConfig(seeds=(3, 3), scenarios=(moving,))


def test_one_real_episode_and_its_summary():
    scenario = Scenario("two slots", {"design": "paper_mixed", "max_slots": 2}, 1.0, 10.0)
    try:
        ep = play((scenario, 0, (492, 656), 2))
    finally:
        close_envs()
    assert ep.correct == ep.slots == 2 and ep.misplaced == ep.dropped == 0
    assert ep.sim_s > 2 and ep.tiles_per_min > 10
    bad = Episode("two slots", 1, 2, 1, 1, 0, 0, 0, 1, 3, 6.0, 10.0, 1.0)
    row = summarise(scenario, [ep, bad])
    assert row["correct"] == 3 and row["tiles"] == 4 and row["correct_fraction"] == 0.75
    assert row["success_rate"] == 0.5 and row["misplaced"] == 1
    assert row["tiles_per_min_worst"] == 10.0 and not row["met"]
    figs = {f.name: f for f in scripted_figures({"seeds": [0, 2], "scenarios": [row]})}
    assert figs["two slots (2 seeds) correct"].passed is False
    assert figs["two slots (2 seeds) tiles/min, worst episode"].passed is True
    assert figs["two slots (2 seeds) misplaced"].passed is False
