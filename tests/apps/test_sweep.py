"""apps.sweep: a tiny sweep (2 training seeds + 1 policy) as Ray tasks on a local 2-CPU Ray."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from apps.sweep import (
    SweepError,
    load_sweep,
    plan,
    run_return,
    run_sweep,
    select_tasks,
)
from envs.tasks import bundled_tasks


def test_sweep_files_are_strict(tmp_path, yaml_file) -> None:
    bad = yaml_file("entries:\n  - {name: x, task: MosaicDecision6-v0}\n")
    with pytest.raises(SweepError, match="exactly one of train, policy or bc_episodes"):
        load_sweep(bad)
    cfg = load_sweep("baselines")
    runs = plan(cfg, tmp_path)
    learned = [r for r in runs if r.entry.train]
    assert learned and all(len(cfg.seeds) >= 3 for _ in learned)


def test_every_registered_task_has_rows() -> None:
    ids = set(bundled_tasks())
    cfg = load_sweep("baselines")
    assert ids == {e.task for e in cfg.entries}
    for task in ids:  # every rung has its random reference row
        assert any(e.task == task and e.policy == "random" for e in cfg.entries), task


def test_task_filter_and_niceness(tmp_path) -> None:
    cfg = select_tasks(load_sweep("baselines"), ["MosaicStream-v0", "MosaicOneTileJoint-v0"])
    runs = plan(cfg, tmp_path, niceness=19)
    assert {r.entry.task for r in runs} == {"MosaicStream-v0", "MosaicOneTileJoint-v0"}
    assert all(r.niceness == 19 for r in runs)
    trained = {r.entry.name for r in runs if r.entry.train}
    assert sorted(r.seed for r in runs if r.entry.train) == sorted([0, 1, 2] * len(trained))
    with pytest.raises(SweepError, match="no sweep entry for task"):
        select_tasks(cfg, ["MosaicDecision6-v0"])
    with pytest.raises(SweepError, match="niceness must be in"):
        plan(cfg, tmp_path, niceness=25)


@pytest.mark.slow
def test_tiny_sweep_on_local_ray(tmp_path) -> None:
    cfg = load_sweep("tiny")
    results = run_sweep(cfg, tmp_path, num_cpus=2, progress=False)
    assert len(results) == 3  # 2 seeds of PPO + the random policy
    ppo = [r for r in results if r["entry"] == "PPO tiny"]
    assert sorted(r["seed"] for r in ppo) == [0, 1] and all(r["timesteps"] >= 128 for r in ppo)
    lines = (tmp_path / "results.jsonl").read_text().splitlines()
    assert len(lines) == 3 and "metrics" in json.loads(lines[0])
    summary = json.loads((tmp_path / "summary.json").read_text())
    row = next(s for s in summary if s["entry"] == "PPO tiny")
    assert row["runs"] == 2 and set(row["estimates"]["success"]) == {"iqm", "lo", "hi", "runs"}
    # The env return of the held-out episodes, per run, read back from their episodes.jsonl.
    for r in ppo:
        eps = [
            json.loads(x) for x in (Path(r["folder"]) / "episodes.jsonl").read_text().splitlines()
        ]
        assert len(eps) == 2 and run_return(r) == pytest.approx(
            sum(e["episode_return"] for e in eps) / 2
        )
    assert row["episode_return"]["runs"] == 2
    head = (tmp_path / "summary.md").read_text().splitlines()[0]
    assert "lost/ep" in head and "return/ep" in head
    assert (tmp_path / "curves.png").stat().st_size > 0
    # A rerun finds every result on disk and starts no Ray task.
    again = run_sweep(cfg, tmp_path, num_cpus=2, progress=False)
    assert len(again) == 3 and len((tmp_path / "results.jsonl").read_text().splitlines()) == 3
