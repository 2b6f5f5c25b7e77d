"""The project's benchmark: every tracked figure, its target and pass/fail, in one table.

Run ``python -m benchmarks`` to run the benchmark scripts (each in its own process, writing its
JSON under ``--out-dir``) and the learned-vs-scripted evaluation, or
``python -m benchmarks --from-json`` to collect the JSON files they already wrote. Prints one
table and writes ``out/bench.json`` (date, machine, every figure) and ``out/bench.md``.

Sources (``BENCHES``): ``benchmarks.shapes`` (describe/assign 10,000 tiles),
``benchmarks.vision`` (recognition on synthetic images), ``benchmarks.cell`` (physics and
rendering speed), ``benchmarks.planner`` (cycle time, tiles/min, tracking),
``benchmarks.env`` (env steps/s, memory), ``benchmarks.perception`` (camera-to-world
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
from configs.files import write_text

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

# Targets of the issues (numbers a user may want to see in one place).
QSHAPE_DESCRIBE_S = 1.0
QSHAPE_ASSIGN_S = 1.0
VISION_CLASS_ROTATION = 0.99
VISION_CANNY_RATIO = 3.0
CELL_REALTIME = 20.0
CELL_RENDER_FPS = 100.0
PLANNER_TILES_PER_MIN = 24.0
PLANNER_RATIO = 1.03
PLANNER_TRACKING_MM = 1.0
PLANNER_PLACE_MM = 1.0
PLANNER_PLACE_DEG = 1.0
SCRIPTED_TILES_PER_MIN = 24.0


@dataclass(frozen=True)
class Figure:
    """One tracked figure.

    Attributes:
        group: Source benchmark (``qshape``, ``vision``, ``cell``, ``planner``, ``env``,
            ``perception``, ``learned``, ``main``).
        name: What is measured.
        value: The measurement (None when the source lacks it).
        unit: Unit of ``value``.
        target: The target as text (``<= 1``, ``>= 24``; "" when reported only).
        passed: True/False against the target; None without a target or a value.
    """

    group: str
    name: str
    value: float | None
    unit: str = ""
    target: str = ""
    passed: bool | None = None


def _get(data: Any, *path: Any) -> Any:
    """``data[p0][p1]...`` or None when any step is missing."""
    for key in path:
        try:
            data = data[key]
        except (KeyError, IndexError, TypeError):
            return None
    return data


def _num(value: Any) -> float | None:
    if isinstance(value, bool):
        return float(value)
    if isinstance(value, int | float):
        return float(value)
    return None


def fig(  # noqa: PLR0917 - terse rows: group, name, value, unit, op, target
    group: str, name: str, value: Any, unit: str = "", op: str = "", target: float | None = None
) -> Figure:
    """A `Figure`, checked against ``op`` (``<=``, ``>=``, ``==``) ``target`` when given."""
    v = _num(value)
    if not op or target is None:
        return Figure(group, name, v, unit)
    text = f"{op} {target:g}"
    if v is None:
        return Figure(group, name, None, unit, text, None)
    ok = {"<=": v <= target, ">=": v >= target, "==": v == target, ">": v > target}[op]
    return Figure(group, name, v, unit, text, bool(ok))


def qshape_figures(d: dict[str, Any]) -> list[Figure]:
    """Figures of ``bench_qshape.json``."""
    g = "qshape"
    n = d.get("tiles", "?")
    return [
        fig(g, f"describe {n} tiles (one by one)", d.get("describe_s"), "s"),
        fig(
            g,
            f"describe {n} tiles (describe_many)",
            d.get("describe_many_s"),
            "s",
            "<=",
            QSHAPE_DESCRIBE_S,
        ),
        fig(
            g,
            f"assign {n} x {n} optimal",
            _get(d, "assign_optimal", "seconds"),
            "s",
            "<=",
            QSHAPE_ASSIGN_S,
        ),
        fig(
            g,
            f"assign {n} x {n} greedy",
            _get(d, "assign_greedy", "seconds"),
            "s",
            "<=",
            QSHAPE_ASSIGN_S,
        ),
        fig(
            g,
            "assign correct class (optimal)",
            _ratio(
                _get(d, "assign_optimal", "correct_class"), _get(d, "assign_optimal", "assigned")
            ),
            "",
            "==",
            1.0,
        ),
        fig(g, "speed-up vs paper's pairwise (greedy)", d.get("speedup_vs_paper_greedy"), "x"),
        *_mix_figures(d),
    ]


QSHAPE_ONE_CLASS_S = 0.5
"""Target [s]: assign 10,000 tiles to 10,000 slots of one class (greedy and optimal)."""


def _mix_figures(d: dict[str, Any]) -> list[Figure]:
    """Assignment on skewed class mixes (one class: targeted; the others reported)."""
    n = d.get("tiles", "?")
    out = []
    for mix, case in (d.get("cases") or {}).items():
        if mix == "balanced":
            continue
        for method in ("optimal", "greedy"):
            target = QSHAPE_ONE_CLASS_S if mix == "one_class" else None
            out.append(
                fig(
                    "qshape",
                    f"assign {n} x {n} {mix.replace('_', ' ')} {method}",
                    _get(case, f"assign_{method}", "seconds"),
                    "s",
                    "<=" if target else "",
                    target,
                )
            )
        out.append(
            fig(
                "qshape",
                f"{mix.replace('_', ' ')}: speed-up vs paper's pairwise (optimal)",
                case.get("speedup_vs_paper_optimal"),
                "x",
            )
        )
    return out


def mural_figures(d: dict[str, Any]) -> list[Figure]:
    """Figures of ``bench_mural.json``: the mural's meshes through the scripted cell."""
    t = d.get("total") or {}
    name = f"{d.get('mural', '?')}, {t.get('meshes', '?')} meshes, {t.get('tiles', '?')} tiles"
    return [
        fig("mural", f"{name} correct", t.get("correct_fraction"), "", ">=", 1.0),
        fig("mural", f"{name} misplaced", t.get("misplaced"), "tiles", "==", 0),
        fig("mural", f"{name} tiles/min (sim)", t.get("tiles_per_min"), "tiles/min"),
        fig("mural", f"{name} wall", t.get("wall_s"), "s"),
    ]


def _ratio(a: Any, b: Any) -> float | None:
    a, b = _num(a), _num(b)
    return a / b if a is not None and b else None


def vision_figures(d: dict[str, Any]) -> list[Figure]:
    """Figures of ``bench_vision.json`` (default noise level ``@1``)."""
    g = "vision"
    levels = d.get("levels") or {}
    default = {k: v for k, v in levels.items() if k.endswith("@1")}
    cr = [v.get("class_and_rotation") for v in default.values()]
    false = [
        (v.get("false_matches_shape") or 0) + (v.get("false_matches_shape_color") or 0)
        for v in default.values()
    ]
    out = [
        fig(
            g,
            "class + rotation within 2 deg (worst design, default noise)",
            min(cr) if cr and None not in cr else None,
            "",
            ">=",
            VISION_CLASS_ROTATION,
        ),
        fig(g, "false matches (default noise)", sum(false) if default else None, "", "==", 0),
        fig(
            g,
            "extract 656x492 / cv2.Canny",
            _get(d, "timing", "ratio_vs_canny_rgb"),
            "x",
            "<=",
            VISION_CANNY_RATIO,
        ),
        fig(g, "extract 656x492, 30 tiles", _get(d, "timing", "extract_ms"), "ms"),
    ]
    return out


def cell_figures(d: dict[str, Any]) -> list[Figure]:
    """Figures of ``bench_cell.json``."""
    g = "cell"
    return [
        fig(
            g,
            "physics, 40 resting tiles",
            _get(d, "physics_resting_arm_still", "realtime_factor"),
            "x real time",
            ">=",
            CELL_REALTIME,
        ),
        fig(
            g,
            "physics, arm moving",
            _get(d, "physics_resting_arm_moving", "realtime_factor"),
            "x real time",
            ">=",
            CELL_REALTIME,
        ),
        fig(
            g,
            "render 2 cameras 128x128",
            _get(d, "render_128", "fps_total"),
            "frames/s",
            ">=",
            CELL_RENDER_FPS,
        ),
        fig(g, "render 2 cameras 656x492", _get(d, "render_656x492", "fps_total"), "frames/s"),
    ]


def planner_figures(d: dict[str, Any]) -> list[Figure]:
    """Figures of ``planner_bench.json`` (first result: paper layout, static belt)."""
    g = "planner"
    results = d.get("results") or []
    paper = results[0] if results else {}
    out = [
        fig(
            g,
            "paper layout tiles/min (sim)",
            paper.get("tiles_per_min"),
            "tiles/min",
            ">=",
            PLANNER_TILES_PER_MIN,
        ),
        fig(
            g, "cycle / lower bound (dwells included)", paper.get("ratio"), "", "<=", PLANNER_RATIO
        ),
        fig(g, "cycle time", paper.get("cycle_s"), "s"),
        fig(
            g,
            "placed within tolerance",
            _ratio(paper.get("placed_within_tolerance"), paper.get("tiles")),
            "",
            "==",
            1.0,
        ),
        fig(g, "tracking error max", paper.get("tracking_max_mm"), "mm", "<=", PLANNER_TRACKING_MM),
        fig(g, "placement error max", paper.get("place_err_max_mm"), "mm", "<=", PLANNER_PLACE_MM),
        fig(
            g,
            "placement yaw error max",
            paper.get("yaw_err_max_deg"),
            "deg",
            "<=",
            PLANNER_PLACE_DEG,
        ),
        fig(g, "planning per cycle (median)", paper.get("plan_ms"), "ms"),
        fig(
            g,
            "ABB standard cycle 25/300/25 mm, blended (ABB: about 0.85 s)",
            d.get("standard_cycle_blended_s"),
            "s",
        ),
        fig(
            g,
            "ABB standard cycle 25/300/25 mm, stop at every corner",
            d.get("standard_cycle_s"),
            "s",
        ),
    ]
    for r in results[1:]:
        label = f"{r.get('layout', '?')} layout, belt {r.get('belt_speed_m_s', '?')} m/s"
        out.append(fig(g, f"{label} tiles/min", r.get("tiles_per_min"), "tiles/min"))
        out.append(
            fig(
                g,
                f"{label} placed within tolerance",
                _ratio(r.get("placed_within_tolerance"), r.get("tiles")),
            )
        )
    return out


def env_figures(d: dict[str, Any]) -> list[Figure]:
    """Figures of ``bench_env.json`` (its own targets, plus async scaling)."""
    g = "env"
    out = []
    for name, t in (d.get("targets") or {}).items():
        op = "<=" if "rss" in name or "_ms" in name else ">="
        out.append(fig(g, name.replace("_", " "), _get(t, "value"), "", op, _get(t, "target")))
    out.append(fig(g, "async vector env speed-up (2 workers)", _get(d, "async", "speedup"), "x"))
    return out


def perception_figures(d: dict[str, Any]) -> list[Figure]:
    """Figures of ``bench_perception.json`` (reported; the cell's targets are downstream)."""
    g = "perception"
    return [
        fig(
            g,
            f"tiles recognised ({d.get('tiles', '?')} tiles)",
            d.get("recognition_accuracy"),
            "",
            "==",
            1.0,
        ),
        fig(g, "pick point error max", d.get("pick_error_mm_max"), "mm"),
        fig(g, "yaw error max", d.get("yaw_error_deg_max"), "deg"),
        fig(g, "calibration reprojection", _get(d, "calibration", "reprojection_px"), "px"),
        fig(g, "perception per image (median)", d.get("wall_ms_per_image_median"), "ms"),
    ]


def learned_figures(d: dict[str, Any]) -> list[Figure]:
    """Figures of ``eval.json``: every policy's row; the learned one(s) against random."""
    g = "learned"
    rows = d.get("rows") or []
    by = {r["policy"]: r for r in rows}
    rand = _get(by, "random", "correct")
    out = []
    for r in rows:
        p = r["policy"]
        kind = p.split("@")[0]
        if kind == "scripted":
            out.append(fig(g, f"{p} success rate", r["success_rate"], "", "==", 1.0))
            out.append(
                fig(
                    g,
                    f"{p} tiles/min (sim)",
                    r["tiles_per_min"],
                    "tiles/min",
                    ">=",
                    SCRIPTED_TILES_PER_MIN,
                )
            )
        elif kind in ("random", "openloop", "identity"):  # references, no target
            out.append(fig(g, f"{p} success rate", r["success_rate"]))
        else:
            out.append(fig(g, f"{p} success rate", r["success_rate"]))
            out.append(fig(g, f"{p} tiles/min (sim)", r["tiles_per_min"], "tiles/min"))
            if rand is not None:
                out.append(
                    fig(
                        g, f"{p} correct/episode vs random", r["correct"], "tiles", ">", float(rand)
                    )
                )
                continue
        out.append(fig(g, f"{p} correct/episode", r["correct"], "tiles"))
        out.append(fig(g, f"{p} wall s/tile", r["wall_s_per_tile"], "s"))
    return out


def scripted_figures(d: dict[str, Any]) -> list[Figure]:
    """Figures of ``bench_scripted.json``: each scenario's correctness and tiles/min."""
    g = "scripted"
    out = []
    for r in d.get("scenarios") or []:
        name = f"{r.get('scenario', '?')} ({r.get('episodes', '?')} seeds)"
        out.append(
            fig(g, f"{name} correct", r.get("correct_fraction"), "", ">=", r.get("target_correct"))
        )
        target = r.get("target_tiles_per_min") or None
        out.append(
            fig(
                g,
                f"{name} tiles/min, worst episode",
                r.get("tiles_per_min_worst"),
                "tiles/min",
                ">=" if target else "",
                target,
            )
        )
        out.append(fig(g, f"{name} misplaced", r.get("misplaced"), "tiles", "==", 0))
    return out


def main_job_figures(d: dict[str, Any]) -> list[Figure]:
    """Figures of the main job's ``report.json``."""
    g = "main"
    return [
        fig(g, "scripted cell success", d.get("success"), "", "==", 1.0),
        fig(
            g,
            "scripted cell correct / tiles",
            _ratio(d.get("correct"), d.get("tiles_total")),
            "",
            "==",
            1.0,
        ),
        fig(
            g,
            "scripted cell tiles/min (sim)",
            d.get("tiles_per_min"),
            "tiles/min",
            ">=",
            SCRIPTED_TILES_PER_MIN,
        ),
        fig(g, "scripted cell misplaced", d.get("misplaced"), "tiles", "==", 0),
        fig(g, "scripted cell wall time", d.get("wall_s"), "s"),
    ]


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
    Bench("qshape", "benchmarks.shapes", "bench_qshape.json", ("--repeat", "1"), qshape_figures),
    Bench("vision", "benchmarks.vision", "bench_vision.json", ("--images", "4"), vision_figures),
    Bench(
        "cell",
        "benchmarks.cell",
        "bench_cell.json",
        ("--seconds", "5", "--frames", "100"),
        cell_figures,
    ),
    Bench("planner", "benchmarks.planner", "planner_bench.json", ("--quick",), planner_figures),
    Bench("env", "benchmarks.env", "bench_env.json", ("--quick",), env_figures, False),
    Bench(
        "perception",
        "benchmarks.perception",
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
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
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
        status[b.name] = {"rc": rc, "wall_s": time.perf_counter() - t0, "error": tail if rc else ""}
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


def machine() -> dict[str, Any]:
    """Where the figures were measured."""
    info: dict[str, Any] = {
        "node": platform.node(),
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "cpus": os.cpu_count(),
        "python": platform.python_version(),
    }
    try:
        info["load_average"] = os.getloadavg()
    except OSError:
        pass
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
    status: dict[str, Any] = {}
    if not args.from_json:
        model = args.model or _latest_model()
        status = run_benches(benches, args.out_dir, args.quick, model, args.timeout)
    figures, sources = collect(benches, args.out_dir)
    for name, st in status.items():
        sources.setdefault(name, {})["run"] = st
    checked = [f for f in figures if f.passed is not None]
    mach = machine()
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


__all__ = ["BENCHES", "Bench", "Figure", "collect", "command", "fig", "main", "table"]

if __name__ == "__main__":
    run_cli(main)
