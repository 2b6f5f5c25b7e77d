"""The project's benchmark: every tracked figure, its target and pass/fail, in one table.

Run ``python -m benchmarks`` to run the benchmark scripts (each in its own process, writing its
JSON under ``--out-dir``) and the learned-vs-scripted evaluation, or
``python -m benchmarks --from-json`` to collect the JSON files they already wrote. Prints one
table and writes ``out/bench.json`` (date, machine, every figure) and ``out/bench.md``.

Sources (``BENCHES``): ``benchmarks.theory.shapes`` (describe/assign 10,000 tiles),
``benchmarks.recognition.synthetic`` (recognition on synthetic images), ``benchmarks.cell``
(physics and rendering speed), ``benchmarks.motion.planner`` (cycle time, tiles/min, tracking),
``benchmarks.env`` (env steps/s, memory), ``benchmarks.recognition.cell_renders`` (camera-to-world
perception), ``benchmarks.scripted`` (the scripted cell over 20 seeds per scenario),
``apps.evaluate`` (learned vs scripted vs random), and the main job's
``out/report.json`` when present (collected only). A missing source gives rows marked
``missing``; a figure without a target is reported only.
"""

from __future__ import annotations

import json
import os
import platform
import shutil
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from apps.cli import CommandParser, run_cli
from benchmarks.figures import (
    Figure,
    cell_figures,
    env_figures,
    learned_figures,
    main_job_figures,
    mural_figures,
    perception_figures,
    planner_figures,
    qshape_figures,
    scripted_figures,
    vision_figures,
)
from configs.files import write_text
from envs.cell.rendering import child_environment

OUT_DIR = Path("out")
"""Default folder of the benchmark JSON files."""
TIMEOUT_S = 900.0
"""Wall-clock limit of one benchmark script [s]."""
EVAL_SEEDS = "1000-1019"
"""Held-out seeds of the learned-vs-scripted evaluation (the ladder's protocol seeds)."""
LEARNED_TASK = "MosaicDecision6-v0"
"""Ladder rung of the learned-vs-scripted rows (its protocol: seeds, episode limit)."""
SHIPPED_MODEL = Path("checkpoints") / LEARNED_TASK / "PPO_state" / "seed_0" / "model.zip"
"""The shipped baseline checkpoint, used when no newer ``runs/*/model.zip`` exists."""


@dataclass(frozen=True)
class Bench:
    """One benchmark source.

    Attributes:
        name: Group name.
        module: ``python -m`` module that writes the JSON ("" when collected only).
        json_name: File name of its JSON under the out folder.
        quick_args: Extra arguments of ``--quick`` runs.
        figures: Extractor of its figures.
        takes_out: The script accepts ``--out PATH``; otherwise it writes ``out/<json_name>``
            (copied to the out folder after the run when that differs).
    """

    name: str
    module: str
    json_name: str
    quick_args: tuple[str, ...]
    figures: Callable[[dict[str, Any]], list[Figure]]
    takes_out: bool = True


BENCHES = (
    Bench(
        "qshape", "benchmarks.theory.shapes", "bench_qshape.json", ("--repeat", "1"), qshape_figures
    ),
    Bench(
        "vision",
        "benchmarks.recognition.synthetic",
        "bench_vision.json",
        ("--images", "4"),
        vision_figures,
    ),
    Bench(
        "cell",
        "benchmarks.cell",
        "bench_cell.json",
        ("--seconds", "5", "--frames", "100"),
        cell_figures,
    ),
    Bench(
        "planner", "benchmarks.motion.planner", "planner_bench.json", ("--quick",), planner_figures
    ),
    Bench("env", "benchmarks.env", "bench_env.json", ("--quick",), env_figures, False),
    Bench(
        "perception",
        "benchmarks.recognition.cell_renders",
        "bench_perception.json",
        ("--seeds", "5"),
        perception_figures,
    ),
    Bench("mural", "benchmarks.mural", "bench_mural.json", ("--meshes", "r0c0"), mural_figures),
    Bench(
        "scripted",
        "benchmarks.scripted",
        "bench_scripted.json",
        ("--seeds", "0-1"),
        scripted_figures,
    ),
    Bench("learned", "apps.evaluate", "eval.json", (), learned_figures),
    Bench("main", "", "report.json", (), main_job_figures),
)
"""Every benchmark source, in table order."""


def _latest_model(runs: Path = Path("runs")) -> Path | None:
    """The newest ``runs/*/model.zip``, else the shipped checkpoint, or None."""
    models = sorted(runs.glob("*/model.zip"), key=lambda p: p.stat().st_mtime)
    if models:
        return models[-1]
    return SHIPPED_MODEL if SHIPPED_MODEL.is_file() else None


def command(bench: Bench, out_dir: Path, quick: bool, model: Path | None) -> list[str] | None:
    """The command line that runs ``bench`` (None: collected only or nothing to run)."""
    if not bench.module:
        return None
    cmd = [sys.executable, "-m", bench.module]
    if bench.module == "apps.evaluate":
        policies = ["scripted", "scripted@execution=dynamic", "random", "openloop"]
        policies += [str(model)] if model else []
        cmd += [
            "--task",
            LEARNED_TASK,
            "--policies",
            *policies,
            "--seeds",
            "1000-1004" if quick else EVAL_SEEDS,
            "--out",
            str(out_dir),
            "--quiet",
        ]
        return cmd
    if bench.takes_out:
        cmd += ["--out", str(out_dir / bench.json_name)]
    return cmd + list(bench.quick_args if quick else ())


def run_benches(
    benches: Sequence[Bench], out_dir: Path, quick: bool, model: Path | None, timeout: float
) -> dict[str, dict[str, Any]]:
    """Run each benchmark script; return per-bench status (rc, wall s, error tail)."""
    status: dict[str, dict[str, Any]] = {}
    env = child_environment()
    for b in benches:
        cmd = command(b, out_dir, quick, model)
        if cmd is None:
            continue
        print(f"running {' '.join(cmd[1:])}", flush=True)
        t0 = time.perf_counter()
        try:
            proc = subprocess.run(
                cmd, capture_output=True, text=True, timeout=timeout, env=env, check=False
            )
            rc, tail = proc.returncode, (proc.stderr or proc.stdout)[-600:]
        except subprocess.TimeoutExpired:
            rc, tail = -1, f"timed out after {timeout:.0f} s"
        status[b.name] = {
            "rc": rc,
            "wall_s": time.perf_counter() - t0,
            "error": tail if rc else "",
            "load_end": load(),
        }
        fixed, wanted = OUT_DIR / b.json_name, out_dir / b.json_name
        if not rc and not b.takes_out and fixed.resolve() != wanted.resolve():
            shutil.copyfile(fixed, wanted)
        if rc:
            print(f"  {b.name} failed (rc {rc}): {tail.strip().splitlines()[-1:]}")
    return status


def collect(benches: Sequence[Bench], out_dir: Path) -> tuple[list[Figure], dict[str, Any]]:
    """Read every source's JSON under ``out_dir``; rows of a missing or bad file are missing."""
    figures: list[Figure] = []
    sources: dict[str, Any] = {}
    for b in benches:
        path = out_dir / b.json_name
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
            mtime = datetime.fromtimestamp(path.stat().st_mtime, UTC)
            sources[b.name] = {"file": str(path), "written": mtime.isoformat(timespec="seconds")}
        except (OSError, json.JSONDecodeError) as exc:
            sources[b.name] = {"file": str(path), "missing": str(exc)}
            figures.append(Figure(b.name, f"({b.json_name} missing)", None))
            continue
        figures.extend(b.figures(data))
    return figures, sources


def _cell(v: float | None) -> str:
    if v is None:
        return "missing"
    if v != 0 and (abs(v) >= 1e4 or abs(v) < 1e-2):
        return f"{v:.3g}"
    return f"{v:.3f}".rstrip("0").rstrip(".") if v != int(v) else f"{int(v)}"


def table(figures: Sequence[Figure]) -> str:
    """The figures as a Markdown table."""
    lines = ["| group | figure | value | unit | target | pass |", "|---|---|---|---|---|---|"]
    for f in figures:
        mark = {True: "PASS", False: "FAIL", None: "-"}[f.passed]
        lines.append(
            f"| {f.group} | {f.name} | {_cell(f.value)} | {f.unit} | {f.target} | {mark} |"
        )
    return "\n".join(lines)


def load() -> dict[str, Any]:
    """The machine's load now: load average (1, 5, 15 min) and the CPUs this process may use."""
    info: dict[str, Any] = {"cpus_usable": len(os.sched_getaffinity(0))}
    try:
        info["load_average"] = list(os.getloadavg())
    except OSError:
        pass
    return info


def machine(start: dict[str, Any] | None = None) -> dict[str, Any]:
    """Where the figures were measured; ``start`` is `load` taken when the run began.

    ``load_average`` is the load at the end (kept for older readers); ``load`` holds the load
    at the ``start`` and ``end`` of the run, each with the CPUs the run could use.
    """
    end = load()
    info: dict[str, Any] = {
        "node": platform.node(),
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "cpus": os.cpu_count(),
        "python": platform.python_version(),
        "load": {"start": start if start is not None else end, "end": end},
    }
    if "load_average" in end:
        info["load_average"] = end["load_average"]
    for mod in ("mujoco", "torch", "stable_baselines3", "gymnasium", "numpy"):
        try:
            info[mod] = __import__(mod).__version__
        except ImportError:
            info[mod] = None
    return info


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line (see the module docstring)."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument("--from-json", action="store_true", help="only collect existing JSON files")
    ap.add_argument("--quick", action="store_true", help="smaller runs of each script")
    ap.add_argument(
        "--only",
        nargs="*",
        default=None,
        metavar="GROUP",
        help=f"subset of {[b.name for b in BENCHES]}",
    )
    ap.add_argument(
        "--model",
        type=Path,
        default=None,
        help="model of the learned row (default: newest runs/*/model.zip, else the shipped one)",
    )
    ap.add_argument("--out-dir", type=Path, default=OUT_DIR, help="folder of the JSON files")
    ap.add_argument("--out", type=Path, default=None, help="bench.json path (default out-dir)")
    ap.add_argument("--timeout", type=float, default=TIMEOUT_S, help="per script [s]")
    args = ap.parse_args(argv)
    benches = [b for b in BENCHES if args.only is None or b.name in args.only]
    unknown = set(args.only or ()) - {b.name for b in BENCHES}
    if unknown:
        ap.error(f"unknown group(s) {sorted(unknown)}; allowed: {[b.name for b in BENCHES]}")
    args.out_dir.mkdir(parents=True, exist_ok=True)
    start = load()
    status: dict[str, Any] = {}
    if not args.from_json:
        model = args.model or _latest_model()
        status = run_benches(benches, args.out_dir, args.quick, model, args.timeout)
    figures, sources = collect(benches, args.out_dir)
    for name, st in status.items():
        sources.setdefault(name, {})["run"] = st
    checked = [f for f in figures if f.passed is not None]
    mach = machine(start)
    summary: dict[str, Any] = {
        "figures": len(figures),
        "with_target": len(checked),
        "passed": sum(bool(f.passed) for f in checked),
        "failed": [f"{f.group}: {f.name}" for f in checked if not f.passed],
    }
    date = datetime.now(UTC).isoformat(timespec="seconds")
    report: dict[str, Any] = {
        "date": date,
        "machine": mach,
        "mode": "from-json" if args.from_json else ("quick" if args.quick else "full"),
        "summary": summary,
        "figures": [asdict(f) for f in figures],
        "sources": sources,
    }
    text = table(figures)
    out = args.out or args.out_dir / "bench.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    write_text(out, json.dumps(report, indent=2))
    write_text(
        out.with_suffix(".md"),
        f"Benchmark {date} on {mach['node']} ({mach['cpus']} CPUs)\n\n{text}\n",
    )
    print(text)
    print(
        f"{summary['passed']}/{summary['with_target']} targets met; wrote {out} and "
        f"{out.with_suffix('.md')}"
    )
    return report


__all__ = ["BENCHES", "Bench", "collect", "command", "main", "table"]

if __name__ == "__main__":
    run_cli(main)
