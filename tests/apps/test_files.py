"""configs.files: result files are written whole or not at all, even under SIGKILL."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from configs.files import (
    PARTIAL_TAG,
    append_line,
    atomic_dir,
    atomic_path,
    complete_lines,
    write_json,
    write_text,
)

ROOT = Path(__file__).resolve().parents[2]
WRITER = """
import sys
from configs.files import write_bytes
path, size = sys.argv[1], int(sys.argv[2])
for i in range(10**6):
    write_bytes(path, bytes([i % 251]) * size)  # each version: one byte value, size bytes
"""


def test_a_failed_write_leaves_the_previous_file(tmp_path) -> None:
    target = tmp_path / "eval.json"
    write_json(target, {"version": 1})
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        tmp.write_text('{"version": 2, "rows": [')  # torn
        raise RuntimeError("killed mid-write")
    assert target.read_text() == '{\n  "version": 1\n}'
    assert sorted(p.name for p in tmp_path.iterdir()) == ["eval.json"]


def test_a_writer_killed_at_random_leaves_a_whole_file(tmp_path) -> None:
    rng = np.random.default_rng(2805)
    target, size = tmp_path / "model.zip", 4_000_000
    for _ in range(3):
        proc = subprocess.Popen(
            [sys.executable, "-c", WRITER, str(target), str(size)],
            cwd=ROOT,
            env={**os.environ, "PYTHONPATH": str(ROOT)},
        )
        while not target.exists():
            time.sleep(0.005)
        time.sleep(float(rng.uniform(0.0, 0.3)))
        os.kill(proc.pid, signal.SIGKILL)
        assert proc.wait() == -signal.SIGKILL
        data = target.read_bytes()
        assert len(data) == size and data == data[:1] * size  # one whole version
    write_text(target, "done")  # the next write clears what the killed writers left
    assert [p.name for p in tmp_path.iterdir()] == ["model.zip"]


def test_a_torn_log_line_is_skipped_and_never_merged(tmp_path) -> None:
    log = tmp_path / "episodes.jsonl"
    log.write_text('{"seed": 1}\n{"seed": 2, "corr')  # killed inside the second line
    assert complete_lines(log) == ['{"seed": 1}']
    append_line(log, '{"seed": 2}')
    assert log.read_text() == '{"seed": 1}\n{"seed": 2}\n'


def test_a_folder_is_replaced_whole(tmp_path) -> None:
    target = tmp_path / "dataset"
    with atomic_dir(target) as tmp:
        (tmp / "a").write_text("old")
    with pytest.raises(RuntimeError), atomic_dir(target) as tmp:
        (tmp / "b").write_text("half")
        raise RuntimeError("killed while recording")
    assert [p.name for p in target.iterdir()] == ["a"]
    with atomic_dir(target) as tmp:
        (tmp / "b").write_text("new")
    assert [p.name for p in target.iterdir()] == ["b"]
    assert not [p for p in tmp_path.iterdir() if PARTIAL_TAG in p.name]
