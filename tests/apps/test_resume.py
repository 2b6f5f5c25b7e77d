"""Kill and rerun: evaluate, train, record_demos and sweep survive SIGKILL at a seeded point.

Each test starts the documented command as a subprocess, kills it (and everything it started)
with SIGKILL at a point drawn from a seeded generator, runs it again and checks the output is
complete, with each result exactly once and every file whole.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from agents.policies import make_policies
from apps.evaluate import EPISODES_FILE, evaluate_policy_set, load_env_overrides
from apps.sweep import RESULT_FILE, RESULTS_LOG, RunSpec, SweepEntry, execute, load_sweep, plan
from apps.train import SUMMARY_FILE, finished_run
from configs.files import PARTIAL_TAG

ROOT = Path(__file__).resolve().parents[2]
KILLED = -signal.SIGKILL
WAIT_S = 300.0
"""Longest wait for a command to reach its kill point or finish [s]."""


def _program(name: str) -> str:
    """The module of a training program (``agents.<name>`` or, after the move, ``apps.<name>``)."""
    for pkg in ("apps", "agents"):
        if (ROOT / pkg / f"{name}.py").is_file() and "run_cli" in (
            ROOT / pkg / f"{name}.py"
        ).read_text(encoding="utf-8"):
            return f"{pkg}.{name}"
    raise AssertionError(f"no program {name}")


def _descendants(pid: int) -> list[int]:
    """Every process started (directly or not) by ``pid`` (Linux ``/proc``)."""
    children: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        children.setdefault(int(fields[1]), []).append(int(stat.parent.name))
    out, todo = [], [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            out.append(child)
            todo.append(child)
    return out


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT), "MUJOCO_GL": "egl"}


def run_and_kill(args: list[str], ready: Callable[[], bool], delay_s: float) -> int:
    """Run ``python -m args``; once ``ready()`` holds, wait ``delay_s`` and SIGKILL it all.

    Returns:
        The command's exit status (``-SIGKILL`` when killed, else it finished first).
    """
    proc = subprocess.Popen(
        [sys.executable, "-m", *args],
        cwd=ROOT,
        env=_env(),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    t0 = time.monotonic()
    while proc.poll() is None and not ready() and time.monotonic() - t0 < WAIT_S:
        time.sleep(0.02)
    time.sleep(delay_s)
    if proc.poll() is None:
        for pid in [proc.pid, *_descendants(proc.pid)]:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
    return proc.wait(timeout=WAIT_S)


def run_to_end(args: list[str]) -> None:
    done = subprocess.run(
        [sys.executable, "-m", *args],
        cwd=ROOT,
        env=_env(),
        capture_output=True,
        text=True,
        check=False,
        timeout=WAIT_S,
    )
    assert done.returncode == 0, done.stderr[-3000:]


def _lines(path: Path) -> int:
    return len(path.read_bytes().split(b"\n")) - 1 if path.is_file() else 0


def _no_partials(folder: Path) -> None:
    left = [p for p in folder.rglob(f"*{PARTIAL_TAG}*")]
    assert not left, left


# ------------------------------------------------------------------------------ evaluate
SEEDS = list(range(1000, 1012))
POLICIES = ["random", "identity"]


def test_evaluate_killed_twice_records_each_episode_once(tmp_path) -> None:
    rng = np.random.default_rng(2801)
    out = tmp_path / "eval"
    log = out / EPISODES_FILE
    args = [_program("evaluate"), "--policies", *POLICIES, "--env-config", "tiny"]
    args += ["--seeds", f"{SEEDS[0]}-{SEEDS[-1]}", "--out", str(out), "--quiet"]
    total = len(SEEDS) * len(POLICIES)
    first, second = sorted(rng.choice(np.arange(1, total - 2), size=2, replace=False))
    for k in (first, second):
        status = run_and_kill(args, lambda k=k: _lines(log) >= k, float(rng.uniform(0, 0.05)))
        assert status == KILLED
        assert not (out / "eval.json").exists()
    run_to_end(args)
    report = json.loads((out / "eval.json").read_text())
    lines = [json.loads(x) for x in log.read_text().splitlines()]
    keys = [(e["policy"], e["seed"]) for e in lines]
    assert len(keys) == len(set(keys)) == total  # each (policy, seed) exactly once, none torn
    for pol in POLICIES:
        assert [e["seed"] for e in report["episodes"][pol]] == SEEDS
    # The resumed episodes are the ones an uninterrupted run plays.
    base = load_env_overrides("tiny")
    _, clean = evaluate_policy_set(make_policies(POLICIES, base), SEEDS)
    for pol in POLICIES:
        got = [(e["seed"], e["correct"], e["episode_return"]) for e in report["episodes"][pol]]
        assert got == [(e.seed, e.correct, e.episode_return) for e in clean[pol]]
    _no_partials(out)


# ------------------------------------------------------------------------------ train
def test_a_killed_training_run_is_unfinished_and_the_sweep_retrains_it(tmp_path) -> None:
    rng = np.random.default_rng(2802)
    run = tmp_path / "MosaicDecision6-v0" / "PPO_tiny" / "seed_0"
    args = [_program("train"), "--config", "tiny", "--out", str(run), "--no-progress"]
    monitor = run / "monitor" / "0.monitor.csv"
    status = run_and_kill(args, monitor.is_file, float(rng.uniform(0.0, 1.5)))
    assert status == KILLED
    assert finished_run(run) is None and not (run / SUMMARY_FILE).exists()
    for ckpt in (run / "checkpoints").glob("*.zip"):
        assert zipfile.is_zipfile(ckpt), ckpt  # checkpoints are whole or absent
    # The sweep's run of that folder trains it again and then evaluates it.
    entry = SweepEntry("PPO tiny", "MosaicDecision6-v0", train="tiny", timesteps=128)
    result = execute(RunSpec(entry, 0, str(run), (1000, 1001)))
    done = finished_run(run)
    assert done is not None and done.timesteps == result["timesteps"] >= 128
    assert json.loads((run / RESULT_FILE).read_text())["row"]["episodes"] == 2
    seeds = [json.loads(x)["seed"] for x in (run / EPISODES_FILE).read_text().splitlines()]
    assert seeds == [1000, 1001]
    _no_partials(run)


# ------------------------------------------------------------------------------ record_demos
DEMO_ENV = ["max_slots=2", "action_mode=pick_place_discrete", "obs_mode=state"]
DEMO_ENV += ["execution=kinematic"]


def test_a_dataset_killed_while_recording_is_absent_then_complete(tmp_path) -> None:
    pytest.importorskip("minari")
    from apps.record_demos import DemoError, load  # noqa: PLC0415

    rng = np.random.default_rng(2803)
    root, ds, episodes = tmp_path / "minari", "mosaic/kill-v0", 40
    args = [_program("record_demos"), "--episodes", str(episodes), "--root", str(root)]
    args += ["--dataset-id", ds, "--expert", "--env", *DEMO_ENV]

    def recording() -> bool:
        return any(root.glob(f".*{PARTIAL_TAG}*"))

    status = run_and_kill(args, recording, float(rng.uniform(0.0, 0.3)))
    assert status == KILLED
    assert not (root / ds).exists()
    with pytest.raises(DemoError, match="no dataset"):
        load(ds, root)
    run_to_end(args)
    data = load(ds, root)
    assert data.total_episodes == episodes
    ids = [int(e.id) for e in data.iterate_episodes()]
    assert ids == list(range(episodes))
    assert not any(root.glob(f".*{PARTIAL_TAG}*"))  # the killed run's staging is gone


# ------------------------------------------------------------------------------ sweep
SWEEP = """seeds: [0, 1]
eval_seeds: [1000, 1001]
entries:
  - {name: random, task: MosaicDecision6-v0, policy: random}
  - {name: PPO tiny, task: MosaicDecision6-v0, train: tiny, timesteps: 128}
"""


@pytest.mark.slow
def test_a_sweep_killed_and_rerun_keeps_each_run_once(tmp_path) -> None:
    rng = np.random.default_rng(2804)
    cfg_path = tmp_path / "sweep.yaml"
    cfg_path.write_text(SWEEP)
    out = tmp_path / "sweep"
    args = [_program("sweep"), "--config", str(cfg_path), "--out", str(out), "--num-cpus", "2"]

    def started() -> bool:
        return any(out.rglob("monitor"))

    status = run_and_kill(args, started, float(rng.uniform(0.0, 3.0)))
    assert status == KILLED
    assert not (out / "summary.json").exists()
    run_to_end(args)
    runs = plan(load_sweep(cfg_path), out)
    for spec in runs:
        folder = Path(spec.folder)
        result = json.loads((folder / RESULT_FILE).read_text())
        assert result["row"]["episodes"] == 2
        seeds = [json.loads(x)["seed"] for x in (folder / EPISODES_FILE).read_text().splitlines()]
        assert seeds == [1000, 1001]
        if spec.entry.train:
            assert finished_run(folder) is not None
    logged = [json.loads(x) for x in (out / RESULTS_LOG).read_text().splitlines()]
    keys = [(r["entry"], r["seed"]) for r in logged]
    assert len(keys) == len(set(keys))
    summary = {r["entry"]: r["runs"] for r in json.loads((out / "summary.json").read_text())}
    assert summary == {"random": 1, "PPO tiny": 2}
