"""The sweep's training-curve plot: no panel of zeros."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from apps.results.sweep_summary import plot_curves


def _run(folder: Path, success: str, returns: list[float]) -> dict[str, object]:
    monitor = folder / "monitor"
    monitor.mkdir(parents=True)
    lines = ['#{"t_start": 0}', "r,l,t,is_success"]
    lines += [f"{r},10,{i},{success}" for i, r in enumerate(returns)]
    (monitor / "0.monitor.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    return {
        "task": "MosaicStream-v0",
        "entry": "PPO state",
        "timesteps": 10 * len(returns),
        "folder": str(folder),
    }


def test_an_all_zero_success_panel_is_left_out(tmp_path) -> None:
    returns = list(np.linspace(-5, 0, 20))
    failing = [_run(tmp_path / f"f{s}", "False", returns) for s in range(2)]
    plot_curves(failing, tmp_path / "failing.png")
    mixed = [*failing, _run(tmp_path / "ok", "True", returns)]
    plot_curves(mixed, tmp_path / "mixed.png")
    w_failing = Image.open(tmp_path / "failing.png").size[0]
    w_mixed = Image.open(tmp_path / "mixed.png").size[0]
    assert w_mixed == 2 * w_failing  # one panel (returns) against two
