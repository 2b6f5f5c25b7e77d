"""The benchmark's figures: each source's JSON read into rows with their targets."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

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
        op = "<=" if "rss" in name or "_ms" in name or name.endswith("_ratio") else ">="
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


__all__ = [
    "CELL_REALTIME",
    "CELL_RENDER_FPS",
    "Figure",
    "PLANNER_PLACE_DEG",
    "PLANNER_PLACE_MM",
    "PLANNER_RATIO",
    "PLANNER_TILES_PER_MIN",
    "PLANNER_TRACKING_MM",
    "QSHAPE_ASSIGN_S",
    "QSHAPE_DESCRIBE_S",
    "QSHAPE_ONE_CLASS_S",
    "SCRIPTED_TILES_PER_MIN",
    "VISION_CANNY_RATIO",
    "VISION_CLASS_ROTATION",
    "cell_figures",
    "env_figures",
    "fig",
    "learned_figures",
    "main_job_figures",
    "mural_figures",
    "perception_figures",
    "planner_figures",
    "qshape_figures",
    "scripted_figures",
    "vision_figures",
]
