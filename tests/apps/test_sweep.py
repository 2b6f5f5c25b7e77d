"""apps.sweep: a tiny sweep (2 training seeds + 1 policy) as Ray tasks on a local 2-CPU Ray."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from agents.protocol import METRICS
from apps.results.sweep_summary import run_return
from apps.sweep import (
    RESULT_FILE,
    RESULTS_LOG,
    SweepError,
    SweepRunsFailed,
    load_sweep,
    plan,
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


FLAKY_POLICY = '''
import os
import signal
from pathlib import Path


class Policy:
    """A random policy whose worker process dies the first time(s) it is built."""

    deaths = 0

    def __init__(self, env):
        marker = Path(os.environ["SWEEP_TEST_DIR"]) / f"{type(self).__name__}.deaths"
        died = int(marker.read_text()) if marker.is_file() else 0
        if died < self.deaths:
            marker.write_text(str(died + 1))
            os.kill(os.getpid(), signal.SIGKILL)  # the Ray worker dies mid-task
        self.action_space = env.action_space

    def predict(self, obs):
        return self.action_space.sample()


class Flaky(Policy):
    deaths = 1


class Doomed(Policy):
    deaths = 100
'''


@pytest.mark.slow
def test_a_dying_worker_is_retried_then_reported_and_the_rest_finish(tmp_path, monkeypatch) -> None:
    (tmp_path / "dying_policies.py").write_text(FLAKY_POLICY)
    monkeypatch.setenv("PYTHONPATH", f"{Path.cwd()}{os.pathsep}{tmp_path}")
    monkeypatch.setenv("SWEEP_TEST_DIR", str(tmp_path))
    cfg = tmp_path / "dying.yaml"
    cfg.write_text(
        "seeds: [0]\neval_seeds: [1000, 1001]\nentries:\n"
        "  - {name: random, task: MosaicDecision6-v0, policy: random}\n"
        "  - {name: flaky, task: MosaicDecision6-v0, policy: 'dying_policies:Flaky'}\n"
        "  - {name: doomed, task: MosaicDecision6-v0, policy: 'dying_policies:Doomed'}\n"
    )
    out = tmp_path / "out"
    with pytest.raises(SweepRunsFailed, match=r"1 of 3 runs failed.*doomed"):
        run_sweep(load_sweep(cfg), out, num_cpus=2, progress=False, max_retries=2)
    assert (tmp_path / "Flaky.deaths").read_text() == "1"  # died once, retried, finished
    assert (tmp_path / "Doomed.deaths").read_text() == "3"  # first try + 2 retries, all died
    logged = {
        json.loads(x)["entry"]: json.loads(x) for x in (out / RESULTS_LOG).read_text().splitlines()
    }
    assert set(logged) == {"random", "flaky", "doomed"}
    assert "error" in logged["doomed"] and "metrics" in logged["flaky"]
    summary = {r["entry"] for r in json.loads((out / "summary.json").read_text())}
    assert summary == {"random", "flaky"}


def test_a_behaviour_cloning_entry_runs_once_per_seed(tmp_path) -> None:
    cfg = tmp_path / "bc.yaml"
    cfg.write_text(
        "seeds: [0, 1, 2]\nentries:\n"
        "  - {name: clone, task: MosaicDecision6-v0, bc_episodes: 4}\n"
        "  - {name: random, task: MosaicDecision6-v0, policy: random}\n"
    )
    runs = plan(load_sweep(cfg), tmp_path)
    clone = [r for r in runs if r.entry.name == "clone"]
    assert [r.seed for r in clone] == [0, 1, 2]
    assert [Path(r.folder).name for r in clone] == ["seed_0", "seed_1", "seed_2"]
    assert [(r.seed, Path(r.folder).name) for r in runs if r.entry.policy] == [(-1, "eval")]


def test_a_rerun_of_a_finished_sweep_starts_no_ray_task(tmp_path, monkeypatch) -> None:
    import ray  # noqa: PLC0415

    cfg = load_sweep("tiny")
    for i, spec in enumerate(plan(cfg, tmp_path)):  # every run finished: its result.json
        metrics = {m: 0.1 * i for m in METRICS}
        result = {"entry": spec.entry.name, "task": spec.entry.task, "seed": spec.seed}
        result |= {"folder": spec.folder, "metrics": metrics}
        Path(spec.folder).mkdir(parents=True)
        (Path(spec.folder) / RESULT_FILE).write_text(json.dumps(result))

    def no_ray(*args, **kwargs):
        raise AssertionError("a finished sweep must not start Ray")

    monkeypatch.setattr(ray, "init", no_ray)
    results = run_sweep(cfg, tmp_path, num_cpus=2, progress=False)
    assert sorted((r["entry"], r["seed"]) for r in results) == [
        ("PPO tiny", 0),
        ("PPO tiny", 1),
        ("random", -1),
    ]
    summary = {r["entry"]: r["runs"] for r in json.loads((tmp_path / "summary.json").read_text())}
    assert summary == {"random": 1, "PPO tiny": 2}


def test_a_row_says_what_ran() -> None:
    from apps.sweep import ran_label  # noqa: PLC0415

    preset = {"max_slots": 6, "obs_mode": "state"}
    assert ran_label("MosaicDecision6-v0", preset, dict(preset)) == "MosaicDecision6-v0"
    shrunk = {**preset, "max_slots": 2}
    assert ran_label("MosaicDecision6-v0", preset, shrunk) == "MosaicDecision6-v0 (max_slots=2)"
