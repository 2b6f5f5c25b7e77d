"""Recognition as a real line sees it: `qshape.extract` + `qshape.match` under its effects.

``python -m benchmarks.recognition.realistic`` draws tiles of the bundled designs as
``benchmarks.recognition.synthetic`` does (default synthetic noise), adds one effect of a real line
at a time (``configs/bench_vision_realistic.yaml``: edge roughness, chipped corners, motion blur on
the moving belt, JPEG, radial lens distortion, a soft shadow, glaze highlights, illumination
gradients, touching tiles, tiles cut by the border), swept from none to strong, then all the
realistic ones at once and everything strong. Per effect and level it reports the class
accuracy (shape only, and shape + colour) over the whole tiles drawn, the rotation error of
correctly classed tiles (against the drawing angle, and against the drawn outline's best
alignment with its design, ``benchmarks.recognition.drawn_rotation``: the orientation the picture
holds; the rotation target is judged on the latter), the fraction right in class *and* rotation
within ``rotation_tol_deg`` of the drawing angle, the worst shape's
accuracy, missed tiles and false matches by shape (a wrong class, a figure where no tile is,
or a tile cut by the border taken for a whole one) and by colour (right shape, another colour's
class). Pictures through a distorting lens are undistorted
with the known lens model before extraction, as a calibrated cell does (``undistort`` in the
config). Written to ``out/bench_vision_realistic.{json,md}``
and plotted to ``out/bench_vision_realistic.png``.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from collections import defaultdict
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from apps.cli import CommandParser, run_cli
from configs import load_config
from configs.files import atomic_path, write_text
from qshape import Description, Tolerances, describe, match_best
from qshape.design import Design
from qshape.geometry import FloatArray
from qshape.synthetic.effects import CameraEffects, undistort, undistort_points
from qshape.synthetic.synth import SynthParams, generate
from qshape.vision.extract import extract_detailed
from qshape.vision.params import ExtractParams

from .drawn_rotation import drawn_angle
from .synthetic import _Refs, _rot_error_deg, pixel_tolerances


@dataclass(frozen=True)
class Level:
    """One effect at one strength.

    Attributes:
        effect: Name of the effect (rows of one effect share it).
        label: The strength, as printed.
        illumination: Illumination gradient (``SynthParams.illumination``) instead of the
            default, dimensionless; None keeps the default.
        effects: The effects' sizes.
        high: When given, each picture draws every field uniformly between ``effects`` and it.
    """

    effect: str
    label: str
    illumination: float | None = None
    effects: CameraEffects = field(default_factory=CameraEffects)
    high: CameraEffects | None = None


@dataclass(frozen=True)
class RealisticBench:
    """Settings of the benchmark (``configs/bench_vision_realistic.yaml``).

    Attributes:
        designs: Bundled designs whose tiles are drawn.
        images: Pictures per design and level.
        tiles_per_image: Tiles wanted per picture (fewer when they do not fit).
        rotation_tol_deg: Rotation error accepted for "class and rotation right", in [deg].
        associate_fraction: A figure belongs to a tile when their centroids are closer than
            this fraction of sqrt(tile area).
        seed: Random seed.
        target_level: Effect name of the level the targets are judged on.
        target_images: Pictures per design at that level.
        plot: Path of the plot (PNG).
        undistort: Undistort pictures taken through a distorting lens with the known lens
            model before extraction (what a calibrated cell does); truth centres likewise.
        levels: The sweep.
    """

    designs: tuple[str, ...] = ()
    images: int = 4
    tiles_per_image: int = 14
    rotation_tol_deg: float = 2.0
    associate_fraction: float = 0.3
    seed: int = 15
    target_level: str = "realistic"
    target_images: int = 60
    plot: str = "out/bench_vision_realistic.png"
    undistort: bool = True
    levels: tuple[Level, ...] = ()


class DesignClasses:
    """Descriptions of one design's classes (shape only; shape and colour), in pixels."""

    def __init__(self, design: Design, s: float, tol: Tolerances) -> None:
        refs = _Refs(design, s)
        self.shape = {k: describe(refs.fig[k], tol) for k in refs.shape}
        self.full = {k: describe(refs.fig[k], tol) for k in refs.full}
        self.slot = {**refs.shape, **refs.full}

    @staticmethod
    def best(
        cand: Description, refs: dict[str, Description], tol: Tolerances, use_color: bool
    ) -> tuple[str | None, Any]:
        """The best-matching class key of ``cand`` among ``refs`` and its match, or Nones."""
        best = match_best(refs, cand, tol, use_color)
        return (None, None) if best is None else best


def seen_picture(
    img: Any, e: CameraEffects, bench: RealisticBench
) -> tuple[np.ndarray, FloatArray]:
    """The picture extraction gets and the truth centres (k, 2) [px] in it."""
    centres = np.array([t.center_px for t in img.tiles], dtype=np.float64).reshape(-1, 2)
    if not bench.undistort or (e.lens_k1 == 0.0 and e.lens_k2 == 0.0):
        return img.image, centres
    h, w = img.image.shape[:2]
    return undistort(img.image, e), undistort_points(centres, e, w, h)


def synth_for(level: Level, sp: SynthParams, rng: np.random.Generator) -> SynthParams:
    """The picture parameters of one picture of ``level`` on top of ``sp``.

    Its effects (drawn from the level's range with ``rng`` where it has one) and illumination.
    """
    e = level.effects if level.high is None else level.effects.between(level.high, rng)
    ill = sp.illumination if level.illumination is None else level.illumination
    return replace(sp, effects=e, illumination=ill)


@dataclass
class _Tally:
    """Counts and errors of one level, gathered tile by tile."""

    c: dict[str, float] = field(default_factory=lambda: defaultdict(float))
    per_shape: dict[str, list[int]] = field(default_factory=lambda: defaultdict(lambda: [0, 0]))
    shape_names: dict[str, str] = field(default_factory=dict)
    rot_errs: list[float] = field(default_factory=list)
    drawn_errs: list[float] = field(default_factory=list)
    failures: list[str] = field(default_factory=list)


def _score_tile(
    tally: _Tally,
    name: str,
    drawn: tuple[Any, FloatArray],
    found: tuple[list[Description], FloatArray, np.ndarray],
    ctx: tuple[DesignClasses, Tolerances, RealisticBench, float],
) -> None:
    """Count one drawn tile of design ``name`` (and its truth centre [px]) in ``tally``.

    ``found``: the figures' descriptions, centroids (k, 2) [px] and which are taken (updated);
    ``ctx``: the classes, tolerances, settings and scale [px/mm].
    """
    t, centre = drawn
    descs, cents, used = found
    classes, tol, bench, s = ctx
    c, per_shape, shape_names = tally.c, tally.per_shape, tally.shape_names
    rot_errs, drawn_errs, failures = tally.rot_errs, tally.drawn_errs, tally.failures
    near = np.hypot(*(cents - centre).T) if len(cents) else np.zeros(0)
    limit = bench.associate_fraction * math.sqrt(t.slot.area) * s
    k = int(np.argmin(near)) if len(near) else -1
    hit = k >= 0 and near[k] <= limit and not used[k]
    if hit:
        used[k] = True
    if t.partial:
        c["partial"] += 1
        if hit and classes.best(descs[k], classes.shape, tol, False)[0] is not None:
            c["false_partial"] += 1
            failures.append(f"{name}: border-cut {t.slot.shape_key} taken as whole")
        return
    c["tiles"] += 1
    per_shape[t.slot.shape_key][0] += 1
    shape_names.setdefault(t.slot.shape_key, f"{name}/{t.slot.shape['kind']}")
    if not hit:
        c["missed"] += 1
        failures.append(f"{name}: {t.slot.shape_key} missed (no figure)")
        return
    key, m = classes.best(descs[k], classes.shape, tol, False)
    ok = key == t.slot.shape_key
    c["shape_correct"] += ok
    per_shape[t.slot.shape_key][1] += ok
    if key is None:
        c["no_match"] += 1
        failures.append(f"{name}: {t.slot.shape_key} not matched: {descs[k]}")
    elif not ok:
        c["false_class"] += 1
        failures.append(f"{name}: {t.slot.shape_key} taken for {key}")
    ok_rot = False
    if ok:
        rep_angle = classes.slot[key].angle  # type: ignore[index]
        err = _rot_error_deg(m, rep_angle, t)
        rot_errs.append(err)
        ok_rot = err <= bench.rotation_tol_deg
        as_drawn = None
        if t.slot.symmetry != 0 and not m.continuous:
            as_drawn = drawn_angle(t, s)
        drawn_err = _rot_error_deg(m, rep_angle, t, as_drawn)
        drawn_errs.append(drawn_err)
        c["class_and_rotation_drawn"] += drawn_err <= bench.rotation_tol_deg
    c["class_and_rotation"] += ok and ok_rot
    key2, _ = classes.best(descs[k], classes.full, tol, True)
    c["full_correct"] += key2 == t.slot.class_key
    c["false_full"] += key2 is not None and key2 != t.slot.class_key


def run_level(  # noqa: PLR0914, PLR0915, PLR0917
    level: Level,
    images: int,
    bench: RealisticBench,
    sp: SynthParams,
    ep: ExtractParams,
    rng: np.random.Generator,
) -> dict[str, Any]:
    """Figures of one level over every design."""
    s = sp.px_per_mm
    tally = _Tally()
    c, per_shape, shape_names = tally.c, tally.per_shape, tally.shape_names
    rot_errs, drawn_errs, failures = tally.rot_errs, tally.drawn_errs, tally.failures
    for name in bench.designs:
        design = Design.load(name)
        tol = pixel_tolerances(design, s)
        classes = DesignClasses(design, s, tol)
        for _ in range(images):
            params = synth_for(level, sp, rng)
            img = generate(design, bench.tiles_per_image, rng, params)
            picture, centres = seen_picture(img, params.effects, bench)
            res = extract_detailed(picture, ep)
            descs = [describe(f, tol) for f in res.figures]
            cents = np.array([f.centroid for f in res.figures]).reshape(-1, 2)
            used = np.zeros(len(res.figures), bool)
            for t, centre in zip(img.tiles, centres, strict=True):
                _score_tile(
                    tally, name, (t, centre), (descs, cents, used), (classes, tol, bench, s)
                )
            for k in np.flatnonzero(~used).tolist():
                if classes.best(descs[k], classes.shape, tol, False)[0] is not None:
                    c["false_spurious"] += 1
                    failures.append(f"{name}: a figure where no tile is matched a class")
    n = max(c["tiles"], 1)
    rot = np.array(rot_errs) if rot_errs else np.zeros(1)
    rot_drawn = np.array(drawn_errs) if drawn_errs else np.zeros(1)
    shapes = {
        f"{shape_names[k]} ({k[:6]})": v[1] / max(v[0], 1) for k, v in sorted(per_shape.items())
    }
    worst = min(shapes, key=shapes.__getitem__) if shapes else ""
    false = c["false_class"] + c["false_full"] + c["false_spurious"] + c["false_partial"]
    return {
        "effect": level.effect,
        "label": level.label,
        "tiles": int(c["tiles"]),
        "partial_tiles": int(c["partial"]),
        "missed": int(c["missed"]),
        "no_match": int(c["no_match"]),
        "class_accuracy": c["shape_correct"] / n,
        "class_color_accuracy": c["full_correct"] / n,
        "class_and_rotation": c["class_and_rotation"] / n,
        "false_matches": int(false),
        "false_class": int(c["false_class"] + c["false_full"]),
        "false_shape": int(c["false_class"] + c["false_spurious"] + c["false_partial"]),
        "false_color": int(c["false_full"]),
        "false_spurious": int(c["false_spurious"]),
        "false_partial": int(c["false_partial"]),
        "rotation_err_deg_p99": float(np.percentile(rot, 99)),
        "rotation_err_deg_max": float(rot.max()),
        "class_and_rotation_drawn": c["class_and_rotation_drawn"] / n,
        "rotation_drawn_err_deg_p99": float(np.percentile(rot_drawn, 99)),
        "rotation_drawn_err_deg_max": float(rot_drawn.max()),
        "worst_shape": worst,
        "worst_shape_accuracy": shapes.get(worst, 1.0),
        "per_shape": shapes,
        "failures": failures[:40],
    }


def markdown(rows: list[dict[str, Any]], date: str) -> str:
    """The table as markdown."""
    lines = [
        f"Recognition under a line's effects ({date}); accuracies over whole tiles drawn.",
        "",
        "| effect | level | tiles | class | class + colour | class + rot <= 2 deg | "
        "rot p99 / max [deg] | rot vs drawn outline p99 / max [deg] | worst shape | missed | "
        "false (shape / colour) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['effect']} | {r['label']} | {r['tiles']} | {100 * r['class_accuracy']:.2f}% "
            f"| {100 * r['class_color_accuracy']:.1f}% | {100 * r['class_and_rotation']:.1f}% "
            f"| {r['rotation_err_deg_p99']:.2f} / {r['rotation_err_deg_max']:.2f} "
            f"| {r['rotation_drawn_err_deg_p99']:.2f} / {r['rotation_drawn_err_deg_max']:.2f} "
            f"| {r['worst_shape']} {100 * r['worst_shape_accuracy']:.0f}% | {r['missed']} "
            f"| {r['false_shape']} / {r['false_color']} |"
        )
    return "\n".join(lines) + "\n"


def plot(rows: list[dict[str, Any]], path: Path) -> None:
    """One panel per effect: class accuracy, class + rotation and false matches per level."""
    import matplotlib  # noqa: PLC0415 (only the benchmark plots)

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    effects = list(dict.fromkeys(r["effect"] for r in rows if r["effect"] != "none"))
    base = next((r for r in rows if r["effect"] == "none"), None)
    cols = 4
    nrows = math.ceil(len(effects) / cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(4.2 * cols, 3.3 * nrows), squeeze=False)
    for ax, eff in zip(axes.ravel(), effects, strict=False):
        sel = ([base] if base is not None else []) + [r for r in rows if r["effect"] == eff]
        x = np.arange(len(sel))
        ax.plot(x, [100 * r["class_accuracy"] for r in sel], "o-", label="class")
        ax.plot(x, [100 * r["class_and_rotation"] for r in sel], "s--", label="class + rot")
        for xi, r in zip(x, sel, strict=True):
            if r["false_shape"]:
                ax.annotate(
                    f"{r['false_shape']} false",
                    (xi, 100 * r["class_accuracy"]),
                    textcoords="offset points",
                    xytext=(0, -14),
                    ha="center",
                    color="red",
                    fontsize=7,
                )
        ax.set_xticks(x, ["none"] + [r["label"] for r in sel[1:]], rotation=25, fontsize=7)
        ax.set_ylim(min(80.0, min(100 * r["class_and_rotation"] for r in sel) - 2), 100.5)
        ax.set_title(eff, fontsize=10)
        ax.grid(alpha=0.3)
    for ax in axes.ravel()[len(effects) :]:
        ax.axis("off")
    axes[0, 0].set_ylabel("% of whole tiles")
    axes[0, 0].legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Run the sweep, print the table, write JSON, markdown and the plot."""
    ap = CommandParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--config", default="bench_vision_realistic")
    ap.add_argument("--images", type=int, default=None, help="pictures per design and level")
    ap.add_argument("--target-images", type=int, default=None)
    ap.add_argument("--only", nargs="*", default=None, help="effect names to run")
    ap.add_argument("--designs", nargs="*", default=None)
    ap.add_argument("--out", type=Path, default=Path("out/bench_vision_realistic.json"))
    args = ap.parse_args(argv)
    cv2.setNumThreads(1)
    bench = load_config(RealisticBench, args.config)
    over: dict[str, Any] = {}
    if args.images is not None:
        over["images"] = args.images
    if args.target_images is not None:
        over["target_images"] = args.target_images
    if args.designs:
        over["designs"] = tuple(args.designs)
    bench = replace(bench, **over)
    sp = SynthParams.load()
    ep = ExtractParams.load()
    rng = np.random.default_rng(bench.seed)
    date = time.strftime("%Y-%m-%d")
    rows: list[dict[str, Any]] = []
    head = (
        f"{'effect':22s} {'level':22s} {'tiles':>5s} {'class':>6s} {'+col':>6s} {'cls+rot':>7s} "
        f"{'rot99':>6s} {'rotmax':>6s} {'miss':>4s} {'false':>7s}  worst shape"
    )
    print(head)
    print("-" * len(head))
    for level in bench.levels:
        if args.only is not None and level.effect not in args.only:
            continue
        n = bench.target_images if level.effect == bench.target_level else bench.images
        t0 = time.perf_counter()
        r = run_level(level, n, bench, sp, ep, rng)
        r["seconds"] = time.perf_counter() - t0
        rows.append(r)
        print(
            f"{r['effect']:22s} {r['label']:22s} {r['tiles']:5d} "
            f"{100 * r['class_accuracy']:6.1f} {100 * r['class_color_accuracy']:6.1f} "
            f"{100 * r['class_and_rotation']:7.1f} {r['rotation_err_deg_p99']:6.2f} "
            f"{r['rotation_err_deg_max']:6.2f} {r['missed']:4d} "
            f"{r['false_shape']:3d}/{r['false_color']:<3d}  "
            f"{r['worst_shape']} {100 * r['worst_shape_accuracy']:.1f}%",
            flush=True,
        )
    target = next((r for r in rows if r["effect"] == bench.target_level), None)
    if target is not None:
        ok = (
            target["class_accuracy"] >= 0.999  # noqa: PLR2004 (the issue's target)
            and min(target["per_shape"].values()) >= 0.999  # noqa: PLR2004
            and target["false_shape"] == 0
            and target["rotation_drawn_err_deg_max"] <= bench.rotation_tol_deg
        )
        print(
            f"target ({bench.target_level}, {target['tiles']} tiles): class "
            f"{100 * target['class_accuracy']:.2f}% (worst shape {target['worst_shape']} "
            f"{100 * target['worst_shape_accuracy']:.2f}%), false by shape {target['false_shape']} "
            f"(by colour {target['false_color']}), "
            f"rotation max {target['rotation_drawn_err_deg_max']:.2f} deg against the drawn "
            f"outline ({target['rotation_err_deg_max']:.2f} against the drawing angle): "
            f"{'PASS' if ok else 'FAIL'}"
        )
        for line in target["failures"]:
            print("  ", line)
    result = {"date": date, "px_per_mm": sp.px_per_mm, "rows": rows}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_text(args.out, json.dumps(result, indent=2))
    write_text(args.out.with_suffix(".md"), markdown(rows, date))
    if rows:
        plot(rows, Path(bench.plot))
    print(f"wrote {args.out}, {args.out.with_suffix('.md')}, {bench.plot}")
    return result


if __name__ == "__main__":
    run_cli(main)
