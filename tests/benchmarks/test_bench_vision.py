"""The old recognition benchmark's command line: scale override and its refusal of bad input."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from apps.cli import UsageError
from benchmarks import vision


def test_pictures_at_another_scale(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "vision.json"
    vision.main(["--images", "1", "--designs", "hexagon", "--px-per-mm", "1.8", "--out", str(out)])
    result = json.loads(out.read_text())
    assert result["params"]["px_per_mm"] == 1.8
    rows = result["levels"]
    assert set(rows) == {"hexagon@0", "hexagon@1", "hexagon@2", "hexagon@3"}
    for row in rows.values():
        assert row["tiles"] > 0
        assert row["false_matches_shape"] == 0 and row["false_matches_shape_color"] == 0
    assert rows["hexagon@0"]["shape_accuracy"] == 1.0
    assert result["timing"]["figures"] == 30
    assert "timing on 656 x 492 px" in capsys.readouterr().out


@pytest.mark.parametrize("bad", ["0", "-2", "nan"])
def test_a_bad_scale_is_refused(bad: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(UsageError, match="--px-per-mm must be a positive number"):
        vision.main(["--timing-only", "--px-per-mm", bad])
