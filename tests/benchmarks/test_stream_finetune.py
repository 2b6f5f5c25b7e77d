"""The fine-tuning benchmark's curve: training episodes against env steps and CPU minutes."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from benchmarks.learned.stream_finetune import plot_curve, running_mean, training_curve

HEADER = '#{"t_start": 0.0, "env_id": "MosaicStream-v2"}\nr,l,t,is_success,filled,cpu_s\n'


def _monitor(run: Path, rows: dict[str, list[str]]) -> None:
    (run / "monitor").mkdir(parents=True)
    for name, lines in rows.items():
        (run / "monitor" / f"{name}.monitor.csv").write_text(
            HEADER + "".join(line + "\n" for line in lines), encoding="utf-8"
        )


def test_the_curve_orders_both_envs_episodes_by_their_end_and_sums_their_steps(
    tmp_path: Path,
) -> None:
    _monitor(
        tmp_path,
        {
            "0": ["19.4,30,15.0,True,1.0,18.0", "12.0,40,45.0,False,0.9375,48.0"],
            "1": ["19.0,25,10.0,True,1.0,12.0"],
        },
    )
    curve = training_curve(tmp_path)
    assert curve[:, 0].tolist() == [25, 55, 95]  # env steps at each end
    assert curve[:, 1] == pytest.approx([0.2, 0.3, 0.8])  # CPU minutes
    assert curve[:, 2].tolist() == [1, 1, 0] and curve[:, 3].tolist() == [19.0, 19.4, 12.0]


def test_the_running_mean_covers_fewer_values_at_the_start() -> None:
    y = np.array([1.0, 0.0, 1.0, 1.0])
    assert running_mean(y, window=2).tolist() == [1.0, 0.5, 0.5, 1.0]


def test_the_curve_figure_is_written(tmp_path: Path) -> None:
    _monitor(tmp_path, {"0": [f"19.0,25,{i}.0,True,1.0,{6 * i}.0" for i in range(1, 30)]})
    out = tmp_path / "img" / "curve.png"
    plot_curve(training_curve(tmp_path), 100, 1.0, [out])
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_clone_file_that_is_no_clone_fails_in_one_line(tmp_path: Path) -> None:
    """``init_clone`` naming a file that is no pair-scorer clone: one line, non-zero exit."""
    bad = tmp_path / "bad.pt"
    bad.write_text("no clone", encoding="utf-8")
    cfg = tmp_path / "ft.yaml"
    preset = Path(__file__).resolve().parents[2] / "configs/train/maskable_ppo_stream_finetune.yaml"
    text = preset.read_text(encoding="utf-8").replace(
        "init_clone: checkpoints/MosaicStream-v1/PairBC_stream/seed_0/bc.pt", f"init_clone: {bad}"
    )
    cfg.write_text(text, encoding="utf-8")
    done = subprocess.run(
        [sys.executable, "-m", "apps.train", "--config", str(cfg), "--out", str(tmp_path / "r")],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode != 0
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "pair-scorer clone" in lines[0], done.stderr
    assert "Traceback" not in done.stderr
