"""The stream's soak row: losses counted tile by tile, its interval, resuming a stopped soak."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from apps.evaluate_results import EpisodeResult
from benchmarks.learned.stream_soak import compare_teacher, deal, soak, tally, wilson
from configs import ConfigError

ROOT = Path(__file__).resolve().parents[2]


def _episode(seed: int, correct: int, *, misplaced: int = 0, lost: int = 0) -> EpisodeResult:
    return EpisodeResult(
        policy="p", seed=seed, design="paper_mixed", success=correct == 16, correct=correct,
        slots=16, misplaced=misplaced, dropped=0, lost=lost, stranded=0, steps=20, sim_s=40.0,
        span_s=40.0, wall_s=5.0, episode_return=0.0, left=16 - correct - misplaced - lost,
    )  # fmt: skip


def test_tally_counts_every_tile_and_a_lost_one_is_not_correct():
    eps = [_episode(0, 16), _episode(1, 14, misplaced=1, lost=1)]
    t = tally(eps, supply_per_min=24.0)
    assert (t.episodes, t.tiles, t.correct, t.misplaced, t.lost) == (2, 32, 30, 1, 1)
    assert t.correct_share == pytest.approx(30 / 32)
    assert t.correct_low < t.correct_share < t.correct_high
    assert t.episodes_complete == 0.5
    assert t.tiles_per_min == pytest.approx((16 + 14) / 2 * 60 / 40)  # the episodes' mean
    assert t.wall_s == 10.0 and t.supply_per_min == 24.0


def test_wilson_interval_at_known_values():
    assert wilson(0, 10) == pytest.approx((0.0, 0.2775), abs=1e-4)
    assert wilson(10, 10) == pytest.approx((0.7225, 1.0), abs=1e-4)
    low, high = wilson(9_800, 10_000)
    assert low == pytest.approx(0.97707, abs=1e-4) and high == pytest.approx(0.98257, abs=1e-4)
    assert wilson(0, 0) == (0.0, 1.0)


def test_seeds_are_dealt_once_each_in_equal_shares():
    parts = deal(list(range(10, 21)), 2)
    assert parts == [[10, 12, 14, 16, 18, 20], [11, 13, 15, 17, 19]]
    assert deal([5], 3) == [[5]]


def test_a_folder_of_another_soak_is_refused(tmp_path):
    (tmp_path / "soak_settings.json").write_text('{"task": "MosaicStream-v1", "policy": "a.pt"}')
    with pytest.raises(ConfigError, match="holds the soak of a.pt on MosaicStream-v1"):
        soak("MosaicStream-v1", "b.pt", 16, first_seed=10_000, workers=1, out=tmp_path)


@pytest.mark.slow
def test_a_soak_resumes_without_playing_an_episode_again(tmp_path):
    """One episode of the shipped clone; the second call finds it in the log and plays none."""
    first = soak("MosaicStream-v1", "checkpoints/MosaicStream-v1/PairBC_stream/seed_0/bc.pt",
                 16, first_seed=10_000, workers=1, out=tmp_path)  # fmt: skip
    log = tmp_path / "worker_0" / "episodes.jsonl"
    lines = log.read_text().splitlines()
    assert len(lines) == 1 and json.loads(lines[0])["seed"] == 10_000
    assert first["episodes"] == 1 and first["tiles"] == 16
    assert first["correct"] + first["misplaced"] + first["lost"] + first["left"] <= 16
    again = soak("MosaicStream-v1", "checkpoints/MosaicStream-v1/PairBC_stream/seed_0/bc.pt",
                 16, first_seed=10_000, workers=1, out=tmp_path)  # fmt: skip
    assert log.read_text().splitlines() == lines
    assert again["correct"] == first["correct"]


@pytest.mark.slow
def test_the_teacher_replays_a_failed_seed_and_fails_where_no_order_saves_every_tile(tmp_path):
    """Seeds 1017 and 1019: both tiles given at reset start too far downstream for any order to
    save; a seed already replayed is not played again, whatever the number of workers."""
    got = compare_teacher("MosaicStream-v1", [1017], workers=1, out=tmp_path)
    assert got == {"teacher_episodes": 1, "teacher_failed_too": 1, "teacher_lost": 1}
    # 1017 again with 1019 on two workers: 1017 is in worker 0's log and is not played again,
    # so 1019 alone is dealt (to worker 0)
    both = compare_teacher("MosaicStream-v1", [1017, 1019], workers=2, out=tmp_path)
    assert both["teacher_episodes"] == 2 and both["teacher_failed_too"] == 2, both
    assert [p.name for p in tmp_path.glob("teacher_*.jsonl")] == ["teacher_0.jsonl"]
    assert len((tmp_path / "teacher_0.jsonl").read_text().splitlines()) == 2


def _wait_forever(seeds: list[int], path: str) -> None:
    """A worker that writes its pid and then waits (module level: spawned workers import it)."""
    Path(path).write_text(str(os.getpid()))
    time.sleep(600)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def test_a_stopped_soak_stops_its_workers(tmp_path):
    """SIGTERM to the soak's process takes its workers down with it: none is left running to
    append to a log a resumed soak reads (that once counted 237 episodes twice)."""
    script = (
        "import sys\n"
        "from pathlib import Path\n"
        "from benchmarks.learned.stream_soak import in_workers\n"
        "from tests.benchmarks.test_stream_soak import _wait_forever\n"
        "in_workers(_wait_forever, [1, 2], 2, Path(sys.argv[1]), 'pid_{}')\n"
    )
    proc = subprocess.Popen([sys.executable, "-c", script, str(tmp_path)], cwd=ROOT)
    pids: list[int] = []
    try:
        deadline = time.monotonic() + 60
        while len(list(tmp_path.glob("pid_*"))) < 2 and time.monotonic() < deadline:
            time.sleep(0.1)
        pids = [int(p.read_text()) for p in sorted(tmp_path.glob("pid_*"))]
        assert len(pids) == 2 and all(_alive(p) for p in pids)
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=30) != 0
        deadline = time.monotonic() + 10
        while any(_alive(p) for p in pids) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not any(_alive(p) for p in pids)
    finally:
        proc.kill()
        for pid in filter(_alive, pids):  # a worker the soak failed to stop
            os.kill(pid, signal.SIGKILL)
