"""Generate the random-designs page's pictures: tiles by shape family, placed and left open.

Two steps, both separate commands (not part of the docs build):

- ``--play`` plays the gallery's designs (`CASES`: the designs the page names as failures,
  and the first designs of each level holding every shape family) with the random-design
  benchmark's own episode (`benchmarks.random_designs.play_design`: the scripted cell from the
  656 x 492 camera pictures), one process, and writes ``docs/design_gallery.json``: per design
  its level, tiles correct and open slots by kind, and per slot its family, whether it was
  filled, and the position and yaw error of the tile filling it. About 5-10 CPU-s per design.
- without it, the pictures are drawn from that file (the designs are drawn again from their
  seeds by `qshape.design.generator`, so the file holds outcomes only) with the project's
  renderer (`qshape.synthetic.render`: tiles in their colours, relevant points dark, curve
  points as rings), into ``docs/img/``:

  - ``random_designs_families.png``: one row per shape family; first the tiles left open,
    then the placed tiles by decreasing yaw error (the hardest ones it still got right);
  - ``random_designs_designs.png``: the named designs whole, open slots outlined in red,
    and the complete designs with the largest yaw errors.

::

    MUJOCO_GL=egl python docs/gen_design_gallery.py --play   # play, then draw
    python docs/gen_design_gallery.py                        # draw from the committed file
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from collections.abc import Iterator
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from qshape.design import Design  # noqa: E402
from qshape.design.generator import DesignGenerator  # noqa: E402
from qshape.design.generator_config import SHAPE_FAMILIES, GeneratorConfig  # noqa: E402
from qshape.synthetic.render import (  # noqa: E402
    RenderParams,
    draw_points,
    fill_tiles,
    mm_to_px,
    render_design,
    to_uint8,
)

RESULTS = DOCS / "design_gallery.json"
"""The played outcomes (committed)."""
IMG_DIR = DOCS / "img"
FAMILIES_PNG = IMG_DIR / "random_designs_families.png"
DESIGNS_PNG = IMG_DIR / "random_designs_designs.png"
MAX_BYTES = 1_000_000
"""Size limit of a committed picture [bytes]."""


@dataclass(frozen=True)
class Case:
    """One design of the gallery.

    Attributes:
        level: Name of its level in ``configs/bench_random_designs.yaml``.
        design: Design index (drawn from ``numpy.random.default_rng(design)``, reset seed too).
        why: What the page says of it ("" for the examples chosen by family).
    """

    level: str
    design: int
    why: str = ""


NAMED = (
    Case("ideal camera, kinematic", 274, "sharp-tipped arc tiles left on the belt"),
    Case("ideal camera, kinematic", 323, "sharp-tipped arc tiles left on the belt"),
    Case("realistic camera, kinematic", 497, "a sharp-tipped arc tile not placed"),
    Case("every glaze, thin tiles, kinematic", 301, "a thin star left unrecognised"),
    Case("every glaze, thin tiles, kinematic", 304, "a tile turned 2.5 deg, a thin star open"),
)
"""The designs the page names as failing (the held-out run and the every-glaze sample)."""
PER_FAMILY = 2
"""Each shape family appears in at least this many of the example designs."""
TILE_COLUMNS = 6
"""Tiles per family row."""
TILE_BOX_MM = 54.0
"""Side of the square each tile is drawn in [mm] (tiles are at most 50 mm across)."""
TILE_PX_PER_MM = 2.4
"""Scale of the family picture's tiles [px/mm]."""
DESIGN_PX_PER_MM = 1.3
"""Scale of the whole designs [px/mm]."""
OPEN_RGB = (220, 30, 30)
"""Outline of an open slot."""


def _bench() -> Any:
    from benchmarks.random_designs import RandomDesignsBenchConfig  # noqa: PLC0415
    from configs import load_config  # noqa: PLC0415

    return load_config(RandomDesignsBenchConfig, "bench_random_designs")


def _level(cfg: Any, name: str) -> Any:
    return next(lv for lv in cfg.levels if lv.name == name)


_DRAWN: dict[tuple[str, int], Design] = {}
"""Designs drawn so far, by (level, index): each is drawn once per run of this script."""


def draw_design(cfg: Any, level_name: str, index: int) -> Design:
    """The design ``index`` of a level, as the benchmark draws it."""
    key = (level_name, index)
    if key not in _DRAWN:
        level = _level(cfg, level_name)
        over = {**cfg.generator_overrides, **level.generator}
        gen = GeneratorConfig.load(cfg.generator, **over)
        _DRAWN[key] = DesignGenerator(gen).draw(
            np.random.default_rng(index), name=f"random_{index}"
        )
    return _DRAWN[key]


def family_of(slot_name: str) -> str:
    """The shape family in a generated slot's name (``c<k>_<family>_<n>``)."""
    return slot_name.split("_")[1]


def example_cases(cfg: Any) -> list[Case]:
    """The first designs of each level until every family is in `PER_FAMILY` of them."""
    named = {(c.level, c.design) for c in NAMED}
    seen = {f: 0 for f in SHAPE_FAMILIES}
    cases: list[Case] = []
    for level in cfg.levels:
        if "dynamic" in level.name:
            continue  # the kinematic levels show the same decisions, faster
        for index in range(*level.designs):
            families = {family_of(s.name) for s in draw_design(cfg, level.name, index).slots}
            if all(seen[f] >= PER_FAMILY for f in families):
                continue
            for f in families:
                seen[f] += 1
            if (level.name, index) not in named:
                cases.append(Case(level.name, index))
            if all(n >= PER_FAMILY for n in seen.values()):
                return cases
            if all(seen[f] >= PER_FAMILY for f in level_families(cfg, level.name)):
                break
    return cases


def level_families(cfg: Any, level_name: str) -> list[str]:
    """The families a level's generator draws."""
    level = _level(cfg, level_name)
    gen = GeneratorConfig.load(cfg.generator, **{**cfg.generator_overrides, **level.generator})
    return [f for f in SHAPE_FAMILIES if gen.families.get(f, 0.0) > 0.0]


def play(cases: list[Case]) -> dict[str, Any]:
    """Play every case with the benchmark's episode; the outcomes as `RESULTS` holds them."""
    from benchmarks.random_designs import play_design  # noqa: PLC0415
    from envs.cell.rendering import use_headless_rendering  # noqa: PLC0415

    use_headless_rendering()
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    cfg = _bench()
    load0 = os.getloadavg()
    c0, t0 = time.process_time(), time.perf_counter()
    rows = []
    with tempfile.TemporaryDirectory(prefix="gallery_") as folder:
        for case in cases:
            row = play_design((_level(cfg, case.level), case.design, cfg, folder))
            rows.append(
                {
                    "level": case.level,
                    "design": case.design,
                    "why": case.why,
                    "slots": row["slots"],
                    "correct": row["correct"],
                    "misplaced": row["misplaced"],
                    "failures": row["failures"],
                    "slot_outcomes": row["_slots"],
                }
            )
            print(
                f"{case.level}: design {case.design}: {row['correct']}/{row['slots']} "
                f"{row['failures'] or ''}",
                flush=True,
            )
    return {
        "date": datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "command": "python docs/gen_design_gallery.py --play",
        "cpu_s": round(time.process_time() - c0, 1),
        "wall_s": round(time.perf_counter() - t0, 1),
        "load_average": {"start": list(load0), "end": list(os.getloadavg())},
        "cpus": os.cpu_count(),
        "designs": rows,
    }


# ------------------------------------------------------------------------------------ drawing
@dataclass(frozen=True)
class TileShot:
    """One tile of the family picture.

    Attributes:
        image: RGB uint8 (H, W, 3).
        caption: One line under it.
        failed: Left open (drawn with a red frame).
        yaw_error_deg: Yaw error of the placed tile [deg] (None: open).
    """

    image: np.ndarray
    caption: str
    failed: bool
    yaw_error_deg: float | None


def tile_image(design: Design, slot_name: str, params: RenderParams) -> np.ndarray:
    """One slot of ``design`` alone, at its turn in the design, relevant points marked."""
    slot = next(s for s in design.slots if s.name == slot_name)
    s = TILE_PX_PER_MM
    side = round(TILE_BOX_MM * s)
    image = np.empty((side, side, 3), np.uint8)
    image[:] = to_uint8(design.grout_color)
    shift = np.array([slot.x, slot.y]) - TILE_BOX_MM / 2.0

    def px(points: np.ndarray) -> np.ndarray:
        return mm_to_px(np.asarray(points) - shift, TILE_BOX_MM, s)

    fill_tiles(image, [(px(slot.outline_mm()), [px(h) for h in slot.holes_mm()])], [slot.color])
    fig = slot.figure()
    boundaries = [(fig.points, fig.curve_mask)] + [(h.points, h.curve_mask) for h in fig.holes]
    for points, curve_mask in boundaries:
        draw_points(image, px(points), curve_mask, params)
    return image


def _shots(data: dict[str, Any], cfg: Any) -> Iterator[tuple[str, TileShot]]:
    """(family, shot) of every distinct (design, class) played, open slots first."""
    params = RenderParams(marker_radius_px=2)
    for row in data["designs"]:
        design = draw_design(cfg, row["level"], row["design"])
        short = row["level"].split(",")[0].replace(" camera", "")
        by_class: dict[str, list[dict[str, Any]]] = {}
        for s in row["slot_outcomes"]:
            by_class.setdefault(s["name"].rsplit("_", 1)[0], []).append(s)
        for outcomes in by_class.values():
            bad = [s for s in outcomes if not s["filled"]]
            if bad:
                s = bad[0]
                what = (
                    f"misplaced, {s['yaw_error_deg']:.1f} deg"
                    if s["misplaced_here"]
                    else "left open"
                )
                caption = f"{row['design']} ({short}): {what}"
                yield (
                    s["family"],
                    TileShot(tile_image(design, s["name"], params), caption, True, None),
                )
                continue
            s = max(outcomes, key=lambda o: o["yaw_error_deg"])
            caption = (
                f"{row['design']}: {s['yaw_error_deg']:.2f} deg, {s['position_error_mm']:.2f} mm"
            )
            yield (
                s["family"],
                TileShot(tile_image(design, s["name"], params), caption, False, s["yaw_error_deg"]),
            )


def families_picture(data: dict[str, Any], cfg: Any, path: Path) -> Path:
    """Write the family picture: per family, open tiles then placed ones by yaw error."""
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    rows: dict[str, list[TileShot]] = {f: [] for f in SHAPE_FAMILIES}
    for family, shot in _shots(data, cfg):
        rows[family].append(shot)
    families = [f for f in SHAPE_FAMILIES if rows[f]]
    fig, axes = plt.subplots(
        len(families), TILE_COLUMNS, figsize=(1.55 * TILE_COLUMNS + 1.0, 1.75 * len(families))
    )
    for r, family in enumerate(families):
        shots = sorted(rows[family], key=lambda t: (not t.failed, -(t.yaw_error_deg or 0.0)))
        for c in range(TILE_COLUMNS):
            ax = axes[r, c]
            ax.set_xticks([])
            ax.set_yticks([])
            if c == 0:
                ax.set_ylabel(family, fontsize=11, fontweight="bold")
            if c >= len(shots):
                ax.axis("off")
                continue
            shot = shots[c]
            ax.imshow(shot.image)
            ax.set_xlabel(shot.caption, fontsize=6.5, color="#b01010" if shot.failed else "#1a1a1a")
            for spine in ax.spines.values():
                spine.set_color("#dc1e1e" if shot.failed else "#9a9a9a")
                spine.set_linewidth(2.5 if shot.failed else 0.6)
    fig.suptitle(
        "Random-design tiles by shape family: red, left open (design, level); grey, placed "
        "(design: yaw, position error), hardest first",
        fontsize=9,
    )
    fig.tight_layout(rect=(0, 0, 1, 0.98))
    return _save(fig, path)


def _outline_open(image: np.ndarray, design: Design, open_names: set[str]) -> np.ndarray:
    import cv2  # noqa: PLC0415

    h = design.mesh_size[1]
    for slot in design.slots:
        if slot.name in open_names:
            pts = mm_to_px(slot.outline_mm(), h, DESIGN_PX_PER_MM)
            cv2.polylines(image, [np.round(pts).astype(np.int32)], True, OPEN_RGB, 3, cv2.LINE_AA)
    return image


def designs_picture(data: dict[str, Any], cfg: Any, path: Path) -> Path:
    """Write the whole-designs picture: the named ones, then complete ones by largest yaw."""
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    named = [r for r in data["designs"] if r["why"]]
    done = [r for r in data["designs"] if not r["why"] and r["correct"] == r["slots"]]
    done.sort(key=lambda r: -max(s["yaw_error_deg"] for s in r["slot_outcomes"]))
    shown = named + done[: max(0, 8 - len(named))]
    cols = 4
    n_rows = -(-len(shown) // cols)
    fig, axes = plt.subplots(n_rows, cols, figsize=(2.6 * cols, 3.0 * n_rows), squeeze=False)
    for ax in axes.flat:
        ax.axis("off")
    for ax, row in zip(axes.flat, shown, strict=False):
        design = draw_design(cfg, row["level"], row["design"])
        open_names = {s["name"] for s in row["slot_outcomes"] if not s["filled"]}
        image = _outline_open(render_design(design, DESIGN_PX_PER_MM), design, open_names)
        ax.imshow(image)
        short = row["level"].split(",")[0].replace(" camera", "")
        if row["why"]:
            kinds = ", ".join(f"{k.replace('_', ' ')} {n}" for k, n in row["failures"].items())
            title = f"{row['design']} ({short}): {row['correct']}/{row['slots']}"
            sub = kinds or "all placed now"
        else:
            worst = max(s["yaw_error_deg"] for s in row["slot_outcomes"])
            title = f"{row['design']} ({short}): {row['correct']}/{row['slots']}"
            sub = f"complete, worst yaw {worst:.2f} deg"
        ax.set_title(f"{title}\n{sub}", fontsize=7.5, color="#b01010" if open_names else "black")
    fig.suptitle(
        "Designs the page names (open slots outlined in red), then complete ones", fontsize=9
    )
    fig.subplots_adjust(left=0.01, right=0.99, bottom=0.01, top=0.89, wspace=0.05, hspace=0.3)
    return _save(fig, path)


def _save(fig: Any, path: Path) -> Path:
    import matplotlib.pyplot as plt  # noqa: PLC0415

    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    size = path.stat().st_size
    if size > MAX_BYTES:
        raise SystemExit(f"error: {path} is {size} bytes, over the {MAX_BYTES} limit")
    return path


def main(argv: list[str] | None = None) -> None:
    """Command line (see the module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--play", action="store_true", help="play the designs first (minutes)")
    ap.add_argument("--results", type=Path, default=RESULTS, help="outcomes JSON")
    ap.add_argument("--out-dir", type=Path, default=IMG_DIR, help="folder of the pictures")
    args = ap.parse_args(argv)
    cfg = _bench()
    if args.play:
        data = play([*NAMED, *example_cases(cfg)])
        args.results.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
        print(f"wrote {args.results} ({data['cpu_s']} CPU-s, {data['wall_s']} s)")
    data = json.loads(args.results.read_text(encoding="utf-8"))
    for path in (
        families_picture(data, cfg, args.out_dir / FAMILIES_PNG.name),
        designs_picture(data, cfg, args.out_dir / DESIGNS_PNG.name),
    ):
        print(f"wrote {path} ({path.stat().st_size // 1000} kB)")


if __name__ == "__main__":
    main()
