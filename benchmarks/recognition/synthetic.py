"""Recognition benchmark of `qshape.extract` + `qshape.match` on synthetic tile images.

``python -m benchmarks.recognition.synthetic`` draws tiles from the bundled designs at random poses
on a belt (``qshape.synthetic.synth``), extracts them, and matches each against the design's shape
classes (shape
only) and shape-and-colour classes. Printed and written to ``out/bench_vision.json``:

- vertex precision / recall within 2 px (tiles without curves; outer boundary),
- class accuracy (shape only; shape + colour), rotation error modulo the tile's symmetry, the
  fraction with the right class *and* rotation within 2 degrees, false matches (a wrong class
  chosen), missed tiles,
- the same figures over a noise sweep (0: clean, 1: default, 2, 3 x every noise source),
- side by side: OpenCV Hu moments (``cv2.matchShapes``) nearest neighbour for class and
  ``cv2.approxPolyDP`` for vertices, on the same traced outlines,
- extraction time vs ``cv2.Canny`` alone on the same 656 x 492 image of 30 tiles (OpenCV's
  colour Canny on the RGB picture, as the target states it; grey and per-channel Canny beside
  it), measured interleaved in one process (see `timing`).
"""

from __future__ import annotations

import argparse
import math
import time
from collections import defaultdict
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from apps.cli import CommandParser, run_cli, write_result
from benchmarks.figures import VISION_CANNY_RATIO
from qshape import Boundary, Figure, Tolerances, match_best
from qshape.design import Design, Slot
from qshape.geometry import FloatArray, wrap_angle
from qshape.synthetic.synth import SynthParams, generate
from qshape.theory.figure import figures_from_outlines
from qshape.vision.extract import extract_detailed
from qshape.vision.params import ExtractParams
from spatial.angles import symmetry_period


@dataclass(frozen=True)
class BenchParams:
    """Benchmark settings.

    Attributes:
        designs: Bundled designs whose tiles are drawn.
        noise_levels: Multipliers of every noise source (1: the default level).
        images: Images per design and noise level.
        tiles_per_image: Tiles drawn per image (fewer when they do not fit).
        vertex_tol_px: A relevant point is found when within this distance, in [px].
        rotation_tol_deg: Rotation error accepted for "class and rotation right", in [deg].
        approx_eps_fraction: ``cv2.approxPolyDP`` epsilon as a fraction of the perimeter.
        associate_fraction: A figure belongs to a true tile when their centroids are closer
            than this fraction of sqrt(tile area).
        timing_tiles: Tiles in the timing image.
        timing_design: Design the timing image's tiles come from.
        timing_px_per_mm: Scale of the timing image, in [px/mm].
        timing_repeats: Timed repetitions (the median is reported).
        seed: Random seed.
    """

    designs: tuple[str, ...] = ("paper_mixed", "square_grid", "hexagon", "trencadis")
    noise_levels: tuple[float, ...] = (0.0, 1.0, 2.0, 3.0)
    images: int = 10
    tiles_per_image: int = 12
    vertex_tol_px: float = 2.0
    rotation_tol_deg: float = 2.0
    approx_eps_fraction: float = 0.02
    associate_fraction: float = 0.3
    timing_tiles: int = 30
    timing_design: str = "hexagon"
    timing_px_per_mm: float = 1.8
    timing_repeats: int = 30
    seed: int = 7


def _scaled(fig: Figure, s: float) -> Figure:
    """A y-up figure scaled by ``s`` about the origin (mm -> px)."""
    holes = [Boundary.make(h.points * s, h.curve_mask) for h in fig.holes]
    return Figure.from_polygon(fig.points * s, holes, fig.color, curve_mask=fig.curve_mask)


def pixel_tolerances(design: Design, px_per_mm: float) -> Tolerances:
    """The bundled tolerances for figures in pixels of a picture of ``design``'s tiles.

    Length tolerances are in the figures' unit: the design's joint and the point tolerance
    (millimetres) scaled to pixels.
    """
    mm = Tolerances.load()
    return replace(
        mm, joint_width=design.joint * px_per_mm, point_tolerance=mm.point_tolerance * px_per_mm
    )


def _pr(truth: np.ndarray, pred: np.ndarray, tol: float) -> tuple[int, int, int, int]:
    """(truth points found, truth count, predicted points confirmed, predicted count)."""
    if len(truth) == 0 or len(pred) == 0:
        return 0, len(truth), 0, len(pred)
    d = np.hypot(*(truth[:, None, :] - pred[None, :, :]).transpose(2, 0, 1))
    hits = int((d.min(axis=1) <= tol).sum())
    return hits, len(truth), int((d.min(axis=0) <= tol).sum()), len(pred)


class _Refs:
    """Class references of one design at one scale."""

    def __init__(self, design: Design, s: float) -> None:
        self.shape: dict[str, Slot] = {}
        self.full: dict[str, Slot] = {}
        for slot in design.slots:
            self.shape.setdefault(slot.shape_key, slot)
            self.full.setdefault(slot.class_key, slot)
        self.fig = {k: _scaled(v.figure(), s) for k, v in {**self.shape, **self.full}.items()}
        self.outline = {
            k: (v.outline_mm() * s).astype(np.float32).reshape(-1, 1, 2)
            for k, v in self.shape.items()
        }


def _classify(
    fig: Figure, refs: dict[str, Slot], figs: dict[str, Figure], tol: Tolerances, use_color: bool
) -> tuple[str | None, Any]:
    best = match_best({key: figs[key] for key in refs}, fig, tol, use_color)
    return (None, None) if best is None else best


def _rot_error_deg(m: Any, rep_angle_deg: float, tile: Any, angle: float | None = None) -> float:
    """Rotation error [deg] of match ``m`` against a drawn tile, modulo the tile's symmetry.

    ``rep_angle_deg``: the angle of the reference figure matched; ``tile``: the drawn tile
    (its angle [rad] and slot symmetry); ``angle``: the tile's orientation [rad] to measure
    against instead of its drawing angle (e.g.
    ``benchmarks.recognition.drawn_rotation.drawn_angle``).
    """
    symmetry = tile.slot.symmetry
    if symmetry == 0 or m.continuous:
        return 0.0
    truth = tile.angle if angle is None else angle
    expected = wrap_angle(math.radians(rep_angle_deg) - truth)
    period = symmetry_period(symmetry)
    return min(abs(math.degrees(math.remainder(r - expected, period))) for r in m.rotations)


def _score_tile(
    c: dict[str, float],
    rot_errs: list[float],
    t: Any,
    found: tuple[Figure, FloatArray],
    ctx: tuple[_Refs, Tolerances, BenchParams],
) -> None:
    """Count (in ``c``, ``rot_errs``) how the figure found on drawn tile ``t`` is classed.

    Also the Hu-moment baseline, and its vertices against the truth and ``approxPolyDP``'s.
    """
    fig, outline = found
    refs, tol, bp = ctx
    # Shape only.
    key, m = _classify(fig, refs.shape, refs.fig, tol, use_color=False)
    ok_shape = key == t.slot.shape_key
    c["shape_correct"] += ok_shape
    c["shape_false"] += key is not None and not ok_shape
    c["shape_none"] += key is None
    ok_rot = False
    if ok_shape:
        err = _rot_error_deg(m, refs.shape[key].angle, t)  # type: ignore[index]
        rot_errs.append(err)
        ok_rot = err <= bp.rotation_tol_deg
    c["shape_and_rotation"] += ok_shape and ok_rot
    # Shape and colour.
    key2, _ = _classify(fig, refs.full, refs.fig, tol, use_color=True)
    ok_full = key2 == t.slot.class_key
    c["full_correct"] += ok_full
    c["full_false"] += key2 is not None and not ok_full
    # Baseline: Hu moments nearest neighbour (shape; shape + colour by colour gate).
    cnt = outline.astype(np.float32).reshape(-1, 1, 2)
    hu = {
        kk: cv2.matchShapes(cnt, ro, cv2.CONTOURS_MATCH_I1, 0.0) for kk, ro in refs.outline.items()
    }
    c["hu_shape_correct"] += min(hu, key=hu.__getitem__) == t.slot.shape_key
    gated = [
        kk
        for kk, sl in refs.full.items()
        if fig.color is not None and math.dist(sl.color, fig.color) <= tol.color_distance
    ] or list(refs.full)
    hu_full = min(gated, key=lambda kk: hu[refs.full[kk].shape_key])
    c["hu_full_correct"] += hu_full == t.slot.class_key
    # Vertices on tiles without curves (outer boundary).
    if not t.curve_mask.any():
        ours = fig.points[~fig.curve_mask]
        a = _pr(t.points_px, ours, bp.vertex_tol_px)
        eps = bp.approx_eps_fraction * cv2.arcLength(cnt, True)
        approx = cv2.approxPolyDP(cnt, eps, True).reshape(-1, 2).astype(np.float64)
        b = _pr(t.points_px, approx, bp.vertex_tol_px)
        for name, v in zip(("hit", "true", "conf", "pred"), a, strict=True):
            c[f"v_{name}"] += v
        for name, v in zip(("hit", "true", "conf", "pred"), b, strict=True):
            c[f"dp_{name}"] += v


def run_level(  # noqa: PLR0917
    design: Design,
    level: float,
    bp: BenchParams,
    sp: SynthParams,
    ep: ExtractParams,
    rng: np.random.Generator,
) -> dict[str, Any]:
    """Figures for one design at one noise level."""
    s = sp.px_per_mm
    params = sp.noise_level(level)
    tol = pixel_tolerances(design, s)
    refs = _Refs(design, s)
    c: dict[str, float] = defaultdict(float)
    rot_errs: list[float] = []
    for _ in range(bp.images):
        img = generate(design, bp.tiles_per_image, rng, params)
        res = extract_detailed(img.image, ep)
        cents = np.array([f.centroid for f in res.figures]).reshape(-1, 2)
        used = np.zeros(len(res.figures), bool)
        for t in img.tiles:
            c["tiles"] += 1
            if len(cents) == 0:
                c["missed"] += 1
                continue
            d = np.hypot(*(cents - t.center_px).T)
            k = int(np.argmin(d))
            if d[k] > bp.associate_fraction * math.sqrt(t.slot.area) * s or used[k]:
                c["missed"] += 1
                continue
            used[k] = True
            _score_tile(c, rot_errs, t, (res.figures[k], res.outlines[k]), (refs, tol, bp))
        c["spurious"] += int((~used).sum())
    n = max(c["tiles"], 1)
    found = max(c["tiles"] - c["missed"], 1)
    rot = np.array(rot_errs) if rot_errs else np.zeros(1)
    return {
        "tiles": int(c["tiles"]),
        "missed": int(c["missed"]),
        "spurious": int(c["spurious"]),
        "shape_accuracy": c["shape_correct"] / n,
        "shape_color_accuracy": c["full_correct"] / n,
        "class_and_rotation": c["shape_and_rotation"] / n,
        "false_matches_shape": int(c["shape_false"]),
        "false_matches_shape_color": int(c["full_false"]),
        "no_match": int(c["shape_none"]),
        "rotation_err_deg_median": float(np.median(rot)),
        "rotation_err_deg_p95": float(np.percentile(rot, 95)),
        "rotation_err_deg_max": float(rot.max()),
        "vertex_precision": c["v_conf"] / max(c["v_pred"], 1),
        "vertex_recall": c["v_hit"] / max(c["v_true"], 1),
        "hu_shape_accuracy": c["hu_shape_correct"] / n,
        "hu_shape_color_accuracy": c["hu_full_correct"] / n,
        "approxpoly_precision": c["dp_conf"] / max(c["dp_pred"], 1),
        "approxpoly_recall": c["dp_hit"] / max(c["dp_true"], 1),
        "found_fraction": found / n,
    }


def _channel_canny(image: np.ndarray, low: float, high: float) -> np.ndarray:
    """Union of one single-channel ``cv2.Canny`` per colour channel.

    Extraction's edge step finds the same edges, from Sobel derivatives it computes itself
    (see ``qshape.vision.segment.canny``).
    """
    r, g, b = cv2.split(image)
    edges = cv2.Canny(r, low, high)
    cv2.bitwise_or(edges, cv2.Canny(g, low, high), dst=edges)
    cv2.bitwise_or(edges, cv2.Canny(b, low, high), dst=edges)
    return edges


def _interleaved(
    steps: dict[str, Any], repeats: int
) -> tuple[dict[str, list[float]], dict[str, list[float]]]:
    """Wall and CPU times [s] of each step over ``repeats`` rounds, after one warm-up call.

    Every step runs once per round, so all of them see the same machine state.
    """
    wall: dict[str, list[float]] = {k: [] for k in steps}
    cpu: dict[str, list[float]] = {k: [] for k in steps}
    for fn in steps.values():
        fn()
    for _ in range(repeats):
        for name, fn in steps.items():
            w0, c0 = time.perf_counter(), time.process_time()
            fn()
            wall[name].append(time.perf_counter() - w0)
            cpu[name].append(time.process_time() - c0)
    return wall, cpu


def _median_time(fn: Any, repeats: int) -> float:
    """Median wall time [s] of ``fn`` over ``repeats`` calls, after one warm-up call."""
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def timing(bp: BenchParams, sp: SynthParams, ep: ExtractParams) -> dict[str, Any]:
    """Extraction time vs cv2.Canny alone on one 656 x 492 image of ``timing_tiles`` tiles.

    The reference (the issue's ratio) is ``cv2.Canny`` called on the same RGB picture with
    extraction's thresholds: OpenCV's colour Canny, which keeps the largest gradient over the
    channels. Beside it, interleaved in the same loop: Canny on the grey picture, and the
    union of one single-channel Canny per channel on the full-size picture (extraction's own
    edge step finds those edges, faster, on its blurred picture, reduced ``canny_reduction``
    times per axis when that is above 1).
    Times are wall clock (``perf_counter``) and, less disturbed by other processes on a shared
    machine, this process's CPU time (``process_time``); every figure is the median over
    ``timing_repeats`` rounds.
    """
    params = replace(sp, px_per_mm=bp.timing_px_per_mm, gap_mm=2.0)
    img = generate(Design.load(bp.timing_design), bp.timing_tiles, bp.seed, params)
    image = img.image
    low, high = ep.canny_low, ep.canny_high
    grey = cv2.cvtColor(image, cv2.COLOR_RGB2GRAY)
    steps: dict[str, Any] = {
        "canny_rgb": lambda: cv2.Canny(image, low, high),
        "extract": lambda: extract_detailed(image, ep),
        "canny_gray": lambda: cv2.Canny(grey, low, high),
        "canny_channels": lambda: _channel_canny(image, low, high),
    }
    res = extract_detailed(image, ep)
    wall, cpu = _interleaved(steps, bp.timing_repeats)
    t = {k: float(np.median(v)) for k, v in wall.items()}
    c = {k: float(np.median(v)) for k, v in cpu.items()}
    pairs = np.array(wall["extract"]) / np.array(wall["canny_rgb"])

    t_outline = _median_time(  # one batch, as extract does it
        lambda: figures_from_outlines(
            res.outlines,
            [()] * len(res.outlines),
            [None] * len(res.outlines),
            ep.outline,
            y_down=True,
        ),
        bp.timing_repeats,
    )
    plain = replace(ep, outline=replace(ep.outline, refine_corners=False))
    t_plain = _median_time(lambda: extract_detailed(image, plain), bp.timing_repeats)
    return {
        "extract_no_refine_ms": 1e3 * t_plain,
        "ratio_no_refine": t_plain / t["canny_rgb"],
        "image": f"{image.shape[1]} x {image.shape[0]}",
        "tiles_drawn": len(img.tiles),
        "figures": len(res.figures),
        "extract_ms": 1e3 * t["extract"],
        "canny_rgb_ms": 1e3 * t["canny_rgb"],
        "canny_gray_ms": 1e3 * t["canny_gray"],
        "canny_channels_ms": 1e3 * t["canny_channels"],
        "ratio_vs_canny_rgb": t["extract"] / t["canny_rgb"],
        "ratio_vs_canny_rgb_pairs": float(np.median(pairs)),
        "ratio_vs_canny_gray": t["extract"] / t["canny_gray"],
        "ratio_vs_canny_channels": t["extract"] / t["canny_channels"],
        "extract_cpu_ms": 1e3 * c["extract"],
        "canny_rgb_cpu_ms": 1e3 * c["canny_rgb"],
        "ratio_vs_canny_rgb_cpu": c["extract"] / c["canny_rgb"],
        "canny_gray_cpu_ms": 1e3 * c["canny_gray"],
        "canny_channels_cpu_ms": 1e3 * c["canny_channels"],
        "ratio_vs_canny_gray_cpu": c["extract"] / c["canny_gray"],
        "ratio_vs_canny_channels_cpu": c["extract"] / c["canny_channels"],
        "outline_simplify_ms": 1e3 * t_outline,
        "image_stages_ms": 1e3 * (t["extract"] - t_outline),
    }


def _row_line(name: str, level: float, r: dict[str, Any]) -> str:
    """One design and noise level's row of the table."""
    return (
        f"{name:12s} {level:5g} {r['tiles']:5d} {r['missed']:4d} "
        f"{100 * r['shape_accuracy']:6.1f} {100 * r['shape_color_accuracy']:6.1f} "
        f"{100 * r['class_and_rotation']:7.1f} "
        f"{r['false_matches_shape'] + r['false_matches_shape_color']:5d} "
        f"{r['rotation_err_deg_median']:6.2f} {r['rotation_err_deg_p95']:6.2f} "
        f"{r['rotation_err_deg_max']:6.2f} {100 * r['vertex_precision']:6.1f} "
        f"{100 * r['vertex_recall']:6.1f} | {100 * r['hu_shape_accuracy']:6.1f} "
        f"{100 * r['hu_shape_color_accuracy']:6.1f} "
        f"{100 * r['approxpoly_precision']:6.1f} {100 * r['approxpoly_recall']:6.1f}"
    )


def _print_timing(t: dict[str, Any]) -> None:
    """Print the timing figures (`timing`)."""
    print(
        f"timing on {t['image']} px, {t['figures']} tiles: extract {t['extract_ms']:.2f} ms "
        f"(image stages {t['image_stages_ms']:.2f} ms + outline simplification and figures "
        f"{t['outline_simplify_ms']:.2f} ms); cv2.Canny on the RGB picture {t['canny_rgb_ms']:.2f} "
        f"ms; interleaved: ratio of medians {t['ratio_vs_canny_rgb']:.2f}x, median of pair "
        f"ratios {t['ratio_vs_canny_rgb_pairs']:.2f}x (target <= {VISION_CANNY_RATIO:g}x); "
        f"CPU time {t['extract_cpu_ms']:.2f} vs {t['canny_rgb_cpu_ms']:.2f} ms: "
        f"{t['ratio_vs_canny_rgb_cpu']:.2f}x"
    )
    print(
        f"  other references (CPU time): Canny on the grey picture {t['canny_gray_cpu_ms']:.2f} ms "
        f"({t['ratio_vs_canny_gray_cpu']:.2f}x), one Canny per channel at full size "
        f"{t['canny_channels_cpu_ms']:.2f} ms ({t['ratio_vs_canny_channels_cpu']:.2f}x); without "
        f"corner refinement (wall): extract {t['extract_no_refine_ms']:.2f} ms "
        f"({t['ratio_no_refine']:.2f}x)"
    )


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Run the benchmark, print the table, write ``out/bench_vision.json``."""
    ap = CommandParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--images", type=int, default=BenchParams.images)
    ap.add_argument("--designs", nargs="*", default=list(BenchParams.designs))
    ap.add_argument("--out", type=Path, default=Path("out/bench_vision.json"))
    ap.add_argument("--timing-only", action="store_true", help="only the extraction timing")
    ap.add_argument(
        "--px-per-mm",
        type=float,
        default=None,
        help="scale of the accuracy pictures in [px/mm] (default: configs/vision.yaml's synth)",
    )
    args = ap.parse_args(argv)
    cv2.setNumThreads(1)
    bp = BenchParams(images=args.images, designs=tuple(args.designs))
    sp = SynthParams.load()
    if args.px_per_mm is not None:
        if not (math.isfinite(args.px_per_mm) and args.px_per_mm > 0.0):
            ap.error(f"--px-per-mm must be a positive number, got {args.px_per_mm}")
        sp = replace(sp, px_per_mm=args.px_per_mm)
    ep = ExtractParams.load()
    rng = np.random.default_rng(bp.seed)
    results: dict[str, Any] = {
        "params": {
            "px_per_mm": sp.px_per_mm,
            "images": bp.images,
            "tiles_per_image": bp.tiles_per_image,
        },
        "levels": {},
    }
    head = (
        f"{'design':12s} {'noise':>5s} {'tiles':>5s} {'miss':>4s} {'shape':>6s} "
        f"{'+col':>6s} {'cls+rot':>7s} {'false':>5s} {'rot50':>6s} {'rot95':>6s} "
        f"{'rotmax':>6s} {'vP':>6s} {'vR':>6s} | {'huS':>6s} {'hu+c':>6s} {'dpP':>6s} "
        f"{'dpR':>6s}"
    )
    print(head)
    print("-" * len(head))
    for name in () if args.timing_only else bp.designs:
        design = Design.load(name)
        for level in bp.noise_levels:
            r = run_level(design, level, bp, sp, ep, rng)
            results["levels"][f"{name}@{level:g}"] = r
            print(_row_line(name, level, r))
    print(
        "columns: accuracies in %; false = wrong class chosen (shape + shape/colour runs); "
        "rot in deg modulo symmetry; vP/vR vertex precision/recall within "
        f"{bp.vertex_tol_px} px; hu = cv2.matchShapes NN; dp = cv2.approxPolyDP "
        f"(eps {bp.approx_eps_fraction} x perimeter)"
    )
    t = timing(bp, sp, ep)
    results["timing"] = t
    _print_timing(t)
    if args.timing_only:  # no accuracy table: nothing written
        return results
    return write_result(args.out, results)


if __name__ == "__main__":
    run_cli(main)
