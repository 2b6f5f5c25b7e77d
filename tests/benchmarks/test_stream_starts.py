"""The stream's starts: which resets no order of picks can save, counted from real resets."""

from __future__ import annotations

import json

import pytest

from benchmarks.stream.starts import StreamStartsConfig, main
from configs import ConfigError


def test_random_starts_include_unsaveable_ones_and_spaced_starts_none(tmp_path):
    config = tmp_path / "starts.yaml"
    config.write_text(
        "tasks: [MosaicStream-v1, MosaicStream-v2]\nseeds: [10000, 10039]\n"
        "first_contact_s: 0.65\nsecond_contact_s: 2.67\n"
    )
    out = tmp_path / "starts.json"
    report = main(["--config", str(config), "--out", str(out)])
    v1, v2 = report["counts"]
    assert (v1["task"], v1["resets"], v2["resets"]) == ("MosaicStream-v1", 40, 40)
    assert 0 < v1["lost_at_fastest"] <= v1["lost_by_schedule"] < 40
    assert len(v1["unsaved_seeds"]) == v1["lost_at_fastest"]
    assert v2["lost_at_fastest"] == v2["lost_by_schedule"] == 0
    # a spaced start keeps its front tile a cycle's travel short of the pick area's edge
    assert v2["downstream_x"][2] < -0.1
    assert json.loads(out.read_text())["counts"][1]["lost_at_fastest"] == 0


def test_bad_settings_are_refused():
    with pytest.raises(ConfigError, match="second_contact_s 0.5 s must come after"):
        StreamStartsConfig(second_contact_s=0.5)
    with pytest.raises(ConfigError, match="seeds"):
        StreamStartsConfig(seeds=(5, 1))
