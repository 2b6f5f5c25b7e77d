"""The command-line error contract: one ``error:`` line, exit 2 for usage, 1 for project errors.

Every program (a module with a ``__main__`` block) ends in ``run_cli(main)``; each bad argument
of the issue that used to print a traceback now prints one line and the documented status.
"""

from __future__ import annotations

import ast
import importlib
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from apps.cli import DEBUG_ENV, EXIT_ERROR, EXIT_USAGE, project_errors, run_cli

ROOT = Path(__file__).resolve().parents[2]
PROGRAM_PACKAGES = ("agents", "apps", "benchmarks")
CHECKPOINT = ROOT / "checkpoints" / "MosaicDecision6-v0" / "PPO_state" / "seed_0"
TASK = ["--task", "MosaicDecision6-v0", "--seeds", "1000"]


def _programs() -> list[str]:
    """Every module of the program packages with a ``__main__`` block (a documented command)."""
    out = []
    for pkg in PROGRAM_PACKAGES:
        for path in sorted((ROOT / pkg).rglob("*.py")):
            if 'if __name__ == "__main__":' in path.read_text(encoding="utf-8"):
                out.append(".".join(path.relative_to(ROOT).with_suffix("").parts))
    return out


PROGRAMS = _programs()


def _main_block_calls(path: Path) -> list[str]:
    """The calls in a module's ``if __name__ == "__main__":`` block, as source text."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in tree.body:
        if isinstance(node, ast.If) and "__main__" in ast.unparse(node.test):
            return [ast.unparse(n) for n in node.body]
    return []


def _run(monkeypatch, capsys, module: str, args: list[str]) -> tuple[int, list[str]]:
    """``python -m module args`` in this process: (exit status, stderr lines)."""
    main = importlib.import_module(module).main
    monkeypatch.setattr(sys, "argv", [module, *args])
    monkeypatch.delenv(DEBUG_ENV, raising=False)
    with pytest.raises(SystemExit) as exc:
        run_cli(main)
    err = capsys.readouterr().err
    return int(exc.value.code or 0), err.strip().splitlines()


def test_the_programs_are_found() -> None:
    for name in ("apps.main", "apps.make_designs", "apps.paper_experiment", "benchmarks.__main__"):
        assert name in PROGRAMS
    assert any(p.endswith(".evaluate") for p in PROGRAMS) and len(PROGRAMS) >= 20


@pytest.mark.parametrize("module", PROGRAMS)
def test_every_program_runs_under_the_contract(module: str) -> None:
    path = ROOT / Path(*module.split(".")).with_suffix(".py")
    assert _main_block_calls(path) == ["run_cli(main)"]


@pytest.mark.parametrize("module", PROGRAMS)
def test_an_unknown_option_is_one_usage_line(monkeypatch, capsys, module: str) -> None:
    code, lines = _run(monkeypatch, capsys, module, ["--no-such-option"])
    assert code == EXIT_USAGE
    assert len(lines) == 1, lines  # the option, or a required argument it lacks
    assert lines[0].startswith("error: ") and "usage:" not in lines[0]


@pytest.fixture(scope="module")
def bad_files(tmp_path_factory) -> dict[str, Path]:
    """A truncated checkpoint (with its run config), random bytes as .pt and .zip, no file."""
    root = tmp_path_factory.mktemp("bad")
    run = root / "truncated"
    run.mkdir()
    shutil.copy(CHECKPOINT / "train_config.yaml", run / "train_config.yaml")
    data = (CHECKPOINT / "model.zip").read_bytes()
    (run / "model.zip").write_bytes(data[: len(data) // 3])
    rng = np.random.default_rng(28)
    (root / "random.pt").write_bytes(rng.bytes(4096))
    (root / "random.zip").write_bytes(rng.bytes(4096))
    return {
        "truncated": run / "model.zip",
        "random_pt": root / "random.pt",
        "random_zip": root / "random.zip",
        "missing_zip": root / "missing.zip",
        "missing_pt": root / "missing.pt",
    }


@pytest.mark.parametrize(
    "bad",
    [
        ("truncated", TASK, EXIT_ERROR, "error: cannot load .*truncated/model.zip"),
        ("random_pt", TASK, EXIT_ERROR, "error: .*random.pt is not a saved policy"),
        ("random_zip", TASK, EXIT_ERROR, "error: cannot load .*random.zip"),
        ("missing_zip", TASK, EXIT_ERROR, "error: unknown policy .*missing.zip"),
        ("missing_pt", TASK, EXIT_ERROR, "error: unknown policy .*missing.pt"),
        ("random", ["--seeds", "abc"], EXIT_USAGE, "error: argument --seeds: bad seed 'abc'"),
        ("random", ["--seeds", "1019-1000"], EXIT_USAGE, "error: .*empty seed range"),
        ("random", ["--task", "NoSuch-v0"], EXIT_ERROR, "error: unknown task 'NoSuch-v0'"),
        ("random", ["--env", "nosuch_key=1"], EXIT_ERROR, "error: .*unknown key.*nosuch_key"),
        ("random", ["--env", "max_slots=-3"], EXIT_ERROR, "error: max_slots must be >= 0"),
    ],
)
def test_each_bad_evaluate_argument_is_one_line(monkeypatch, capsys, tmp_path, bad_files, bad):
    case, args, status, message = bad
    policy = str(bad_files.get(case, case))
    argv = ["--policies", policy, *args, "--out", str(tmp_path), "--quiet"]
    code, lines = _run(monkeypatch, capsys, _module("evaluate"), argv)
    assert code == status
    assert len(lines) == 1, lines
    assert re.match(message, lines[0]), lines[0]
    assert not (tmp_path / "eval.json").exists()


def _module(name: str) -> str:
    """The importable module of a training program (wherever the programs live)."""
    return next(p for p in PROGRAMS if p.rsplit(".", 1)[-1] == name)


@pytest.mark.parametrize(
    "bad",
    [
        ("train", ["--config", "no_such_preset"], "error: .*no_such_preset"),
        ("sweep", ["--config", "no_such_sweep"], "error: .*no_such_sweep"),
        ("record_demos", ["--task", "NoSuch-v0", "--episodes", "1"], "error: unknown task"),
        ("decision", ["--dataset-id", "mosaic/none-v0", "--root", "{tmp}"], "error: no dataset"),
        ("main", ["--belt-speed", "-1", "--out", "{tmp}"], "error: run: belt_speed"),
    ],
)
def test_each_program_reports_a_project_error_in_one_line(monkeypatch, capsys, tmp_path, bad):
    name, args, message = bad
    argv = [a.format(tmp=tmp_path) for a in args]
    module = "apps.main" if name == "main" else _module(name)
    code, lines = _run(monkeypatch, capsys, module, argv)
    assert code == EXIT_ERROR
    assert len(lines) == 1 and re.match(message, lines[0]), lines


def _command(args: list[str], **env: str) -> subprocess.CompletedProcess[str]:
    base = {k: v for k, v in os.environ.items() if k != DEBUG_ENV}
    return subprocess.run(
        [sys.executable, "-m", _module("evaluate"), *args],
        cwd=ROOT,
        env={**base, "PYTHONPATH": str(ROOT), **env},
        capture_output=True,
        text=True,
        check=False,
        timeout=300,
    )


def test_command_line_project_error_and_debug_traceback(tmp_path) -> None:
    """A real process: one line and status 1; with ``--debug`` Python's traceback, status 1."""
    bad = ["--policies", "random", "--env", "max_slots=-3", "--out", str(tmp_path)]
    plain = _command(bad)
    assert plain.returncode == EXIT_ERROR
    assert plain.stderr.strip().splitlines() == ["error: max_slots must be >= 0, got -3"]
    shown = _command([*bad, "--debug"])
    assert shown.returncode == 1
    assert "Traceback (most recent call last)" in shown.stderr
    assert shown.stderr.strip().splitlines()[-1].endswith("max_slots must be >= 0, got -3")


def test_debug_variable_lets_the_error_out_and_a_usage_error_is_one_line(
    monkeypatch, capsys, tmp_path
) -> None:
    """``MOSAIC_DEBUG=1`` acts as ``--debug``; a bad ``--seeds`` is one line with status 2.

    In this process (a new one costs seconds of imports): with the variable the error leaves
    `run_cli`, so Python prints its traceback and exits 1, as the real process above shows.
    """
    module = _module("evaluate")
    main = importlib.import_module(module).main
    bad = ["--policies", "random", "--env", "max_slots=-3", "--out", str(tmp_path)]
    monkeypatch.setattr(sys, "argv", [module, *bad])
    monkeypatch.setenv(DEBUG_ENV, "1")
    with pytest.raises(project_errors(), match="max_slots must be >= 0, got -3"):
        run_cli(main)
    code, lines = _run(monkeypatch, capsys, module, ["--policies", "random", "--seeds", "abc"])
    assert code == EXIT_USAGE
    assert lines == ["error: argument --seeds: bad seed 'abc': use 1000-1019 or 1,2,3"]


def test_an_unexpected_exception_keeps_its_traceback(tmp_path) -> None:
    (tmp_path / "broken_policy.py").write_text(
        "def Policy(env):\n    raise RuntimeError('a bug in the policy')\n"
    )
    proc = subprocess.run(
        [sys.executable, "-m", _module("evaluate"), "--policies", "broken_policy:Policy"]
        + ["--seeds", "1000", "--out", str(tmp_path / "out")],
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": f"{ROOT}{os.pathsep}{tmp_path}"},
        capture_output=True,
        text=True,
        check=False,
        timeout=300,
    )
    assert proc.returncode == 1
    assert "Traceback (most recent call last)" in proc.stderr
    assert proc.stderr.strip().splitlines()[-1] == "RuntimeError: a bug in the policy"
