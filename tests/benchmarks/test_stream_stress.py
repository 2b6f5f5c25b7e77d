"""The stream's stress benchmark: a stream faster than the cell's cycle loses tiles and says so."""

from __future__ import annotations

from dataclasses import replace

import pytest

from apps.evaluate import task_protocol
from benchmarks.stream.stress import (
    StreamStressConfig,
    StressRun,
    highest_kept_up,
    stress_run,
    table,
)
from configs import ConfigError


def _run(period: float, fed: int, correct: int, lost: int) -> StressRun:
    return StressRun(0.1, period, 1, fed, correct, lost, 0, lost, 60 / period, 20.0, 2.3, 26.1, 1.0)


def test_a_run_that_loses_tiles_is_reported_as_not_kept_up():
    runs = [_run(2.5, 100, 100, 0), _run(1.8, 100, 80, 20)]
    text = table(runs)
    assert "cannot keep up: 20 of 100 tiles not placed" in text
    assert "highest supply kept up with 24.0 tiles/min (period 2.5 s)" in text
    assert highest_kept_up(runs, 0.1) is runs[0]
    assert highest_kept_up([runs[1]], 0.1) is None
    assert "no supply rate tried is kept up with" in table([runs[1]])


def test_bad_settings_are_refused():
    with pytest.raises(ConfigError, match="periods"):
        StreamStressConfig(periods=(2.5, -1.0))


@pytest.mark.slow
def test_a_stream_faster_than_the_cycle_loses_tiles_and_says_so():
    base, _ = task_protocol("MosaicStream-v1")
    cfg = replace(StreamStressConfig(), tiles=6, first_seed=0)
    run = stress_run(
        cfg, 0.1, 1.0, {**base, "max_slots": 6}
    )  # a tile a second: faster than a cycle
    assert run.fed == 6
    assert run.lost > 0 and run.correct < run.fed and not run.keeps_up
    assert run.given_up > 0  # the scheduler gave up tiles it could not reach in time
    assert run.cycle_s > 1.0 and run.sustained_per_min <= run.cycle_bound_per_min * 1.05
    assert "cannot keep up" in table([run])
