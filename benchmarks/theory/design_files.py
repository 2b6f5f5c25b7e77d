"""Benchmark of SVG and DXF design files: loading a 1,000-tile mural, and round trips.

Run ``python -m benchmarks.theory.design_files [--repeat N]``. The bundled mural (``sunset``, 1,000
tesserae) laid out as one design is written as SVG and DXF (`Design.to_svg`, `Design.to_dxf`)
and loaded back (`Design.load`: parsing, curve fitting, shape classes, the layout checks) the
fastest of ``--repeat`` times, after one warm-up load (the parsers' imports); target: under 2 s
each. Every bundled design goes through both round trips: the largest distance between a
slot's outline before and after (either way) and of its centroid, target 0.01 mm. Prints a
table and writes ``out/bench_design_files.json``.
"""

from __future__ import annotations

import json
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import shapely

from apps.cli import CommandParser, run_cli
from configs.files import write_text
from qshape.design import Design, bundled_designs
from qshape.design.mural import Mural

OUT = Path("out/bench_design_files.json")
"""Default output file."""
MAX_LOAD_S = 2.0
"""Target: seconds to load a 1,000-tile drawing."""
MAX_ROUND_TRIP_MM = 0.01
"""Target: largest outline or centroid change of a slot through a save and a load [mm]."""
SAMPLE_STEP_MM = 0.2
"""Outline sampling of the round-trip comparison [mm]."""


def slot_change_mm(a: Design, b: Design) -> float:
    """Largest distance between the slots' outlines (both ways) and centroids, [mm].

    Raises:
        ValueError: The designs' slot names differ.
    """
    if [s.name for s in a.slots] != [s.name for s in b.slots]:
        raise ValueError("the slot names differ")
    worst = 0.0
    for s, t in zip(a.slots, b.slots, strict=True):
        for loops in zip((s.path.outer, *s.path.holes), (t.path.outer, *t.path.holes), strict=True):
            pa, pb = (lp.dense(SAMPLE_STEP_MM) for lp in loops)
            ra, rb = shapely.LinearRing(pa), shapely.LinearRing(pb)
            d1 = shapely.distance(ra, shapely.points(pb)).max()
            d2 = shapely.distance(rb, shapely.points(pa)).max()
            worst = max(worst, float(d1), float(d2))
        worst = max(worst, float(np.hypot(s.x - t.x, s.y - t.y)))
    return worst


def load_seconds(path: Path, repeat: int) -> tuple[float, Design]:
    """Fastest of ``repeat`` loads of ``path`` after a warm-up load, and the design."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        design = Design.load(path)
        best = float("inf")
        for _ in range(repeat):
            t0 = time.perf_counter()
            design = Design.load(path)
            best = min(best, time.perf_counter() - t0)
    return best, design


def run(repeat: int) -> dict[str, Any]:
    """Every figure of the benchmark (see the module docstring)."""
    mural = Mural.load("sunset").design()
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory() as tmp:
        for fmt in ("svg", "dxf"):
            path = Path(tmp) / f"mural.{fmt}"
            mural.to_svg(path) if fmt == "svg" else mural.to_dxf(path)
            seconds, back = load_seconds(path, repeat)
            rows.append(
                {
                    "what": f"load a {len(mural.slots):,}-tile {fmt.upper()} mural",
                    "seconds": seconds,
                    "tiles": len(back.slots),
                    "change_mm": slot_change_mm(mural, back),
                    "met": seconds < MAX_LOAD_S,
                }
            )
        trips: list[dict[str, Any]] = []
        for name in bundled_designs():
            design = Design.load(name)
            for fmt in ("svg", "dxf"):
                path = Path(tmp) / f"{name}.{fmt}"
                design.to_svg(path) if fmt == "svg" else design.to_dxf(path)
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    back = Design.load(path)
                change = slot_change_mm(design, back)
                trips.append({"design": name, "format": fmt, "change_mm": change})
    worst = max(float(t["change_mm"]) for t in trips)
    return {
        "loads": rows,
        "round_trips": trips,
        "round_trip_worst_mm": worst,
        "round_trip_met": worst <= MAX_ROUND_TRIP_MM,
        "targets": {"load_s": MAX_LOAD_S, "round_trip_mm": MAX_ROUND_TRIP_MM},
    }


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line: run, print the table, write the JSON."""
    p = CommandParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeat", type=int, default=3, help="timed loads per file (fastest kept)")
    p.add_argument("--out", type=Path, default=OUT)
    args = p.parse_args(argv)
    result = run(max(1, args.repeat))
    for r in result["loads"]:
        verdict = "met" if r["met"] else "NOT MET"
        print(
            f"{r['what']:34s} {r['seconds']:6.2f} s  (target < {MAX_LOAD_S:g} s: {verdict}), "
            f"slots within {r['change_mm']:.5f} mm"
        )
    verdict = "met" if result["round_trip_met"] else "NOT MET"
    print(
        f"round trips of {len(result['round_trips'])} (design, format) pairs: worst slot change "
        f"{result['round_trip_worst_mm']:.5f} mm (target <= {MAX_ROUND_TRIP_MM} mm: {verdict})"
    )
    write_text(args.out, json.dumps(result, indent=2))
    print(f"wrote {args.out}")
    return result


if __name__ == "__main__":
    run_cli(main)
