r"""The low-level baseline table and training curves from run folders and an evaluation.

Run::

    python -m apps.results.lowlevel_report --runs RLPD=runs/rlpd/seed_0 SAC=runs/sac/seed_0 \
        BC=runs/bc/seed_0 --eval out/eval_lowlevel --out docs/low_level_curves.png

Each ``NAME=FOLDER`` is an ``apps.train`` run folder (its ``summary.json``: env steps,
gradient steps, CPU time; its ``monitor/`` CSVs: the training curve); ``--eval`` is an
``apps.evaluate`` output folder whose ``episodes.jsonl`` holds the held-out episodes of each
policy (labelled by its folder name). The table gives the success rate's IQM with a 95 %
stratified-bootstrap interval (``rliable``, `agents.protocol.iqm_ci`) over the runs given
per name (one run: over its held-out episodes, each episode one value, the interval then
says how far 20 episodes pin the rate down), and the compute. The curves are
`apps.results.sweep_summary.plot_curves`.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from agents.protocol import iqm_ci
from apps.cli import CommandParser, run_cli
from apps.results.sweep_summary import plot_curves
from configs import ConfigError

SECONDS_PER_MINUTE = 60.0


def _runs(pairs: Sequence[str]) -> dict[str, list[Path]]:
    out: dict[str, list[Path]] = {}
    for pair in pairs:
        if "=" not in pair:
            raise ConfigError(f"--runs wants NAME=FOLDER, got {pair!r}")
        name, folder = pair.split("=", 1)
        out.setdefault(name, []).append(Path(folder))
    return out


def _episodes(eval_dir: Path) -> dict[str, list[float]]:
    """Per policy label: the success (0/1) of each held-out episode."""
    out: dict[str, list[float]] = {}
    for line in (eval_dir / "episodes.jsonl").read_text(encoding="utf-8").splitlines():
        rec = json.loads(line)
        out.setdefault(rec["policy"], []).append(float(rec["success"]))
    return out


def _steps(folder: Path) -> int:
    """Env steps of a run (its ``summary.json``)."""
    return int(json.loads((folder / "summary.json").read_text(encoding="utf-8"))["timesteps"])


def table(runs: dict[str, list[Path]], eval_dir: Path) -> list[dict[str, Any]]:
    """One row per name: success IQM [95 % CI], episodes, env steps, gradient steps, CPU min."""
    episodes = _episodes(eval_dir)
    rows = []
    for name, folders in runs.items():
        labels = [  # as agents.policies names a checkpoint's run folder
            f"{f.parent.name}/{f.name}" if f.name.startswith("seed_") else f.name for f in folders
        ]
        scores = [episodes.get(label, []) for label in labels]
        if not all(scores):
            raise ConfigError(f"{name}: no evaluated episodes of {labels} in {eval_dir}")
        per_run = [sum(s) / len(s) for s in scores]
        est = iqm_ci(per_run if len(per_run) > 1 else scores[0])
        sums = [json.loads((f / "summary.json").read_text(encoding="utf-8")) for f in folders]
        rows.append(
            {
                "name": name,
                "success": est.text(),
                "episodes": sum(len(s) for s in scores),
                "env_steps": [s["timesteps"] for s in sums],
                "gradient_steps": [s.get("gradient_steps", 0) for s in sums],
                "cpu_min": [
                    round(s.get("cpu_s", float("nan")) / SECONDS_PER_MINUTE, 1) for s in sums
                ],
            }
        )
    return rows


def main(argv: list[str] | None = None) -> list[dict[str, Any]]:
    """Command line (see the module docstring)."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", nargs="+", required=True, metavar="NAME=FOLDER")
    ap.add_argument("--eval", type=Path, required=True, help="apps.evaluate output folder")
    ap.add_argument("--task", default="MosaicOneTile-v0")
    ap.add_argument("--out", type=Path, default=Path("out/low_level_curves.png"))
    args = ap.parse_args(argv)
    runs = _runs(args.runs)
    rows = table(runs, args.eval)
    print("| row | success IQM [95 % CI] | episodes | env steps | gradient steps | CPU-min |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        print(
            f"| {r['name']} | {r['success']} | {r['episodes']} | {r['env_steps']} | "
            f"{r['gradient_steps']} | {r['cpu_min']} |"
        )
    results = [
        {"task": args.task, "entry": name, "folder": str(f), "timesteps": _steps(f)}
        for name, folders in runs.items()
        for f in folders
    ]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    plot_curves(results, args.out)
    print(f"curves: {args.out}")
    return rows


if __name__ == "__main__":
    run_cli(main)
