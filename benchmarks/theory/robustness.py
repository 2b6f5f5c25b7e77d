"""qshape robustness benchmark: every entry point at its documented cap, and just above it.

For each cap of ``configs/qshape.yaml`` (``limits``) this times the entry point on an input at
the cap (a valid, worst-case-shaped input: the most relevant points, the longest text, the
densest outline) and checks that an input just above the cap is refused with qshape's own error
in well under a second. The issue's adversarial inputs (10,000-digit counts, 10,000-vertex
outlines, a 10^6-sided polygon, figures at 1e9 .. 1e14 from the origin) are replayed too.

    python -m benchmarks.theory.robustness   # prints a table, writes out/bench_robustness.json

Wall-clock times are of one process on a shared machine: read them as orders of magnitude.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

import qshape
from apps.cli import CommandParser, run_cli
from configs.files import write_text
from qshape.limits import default_limits
from qshape.theory.keys import clear_key_caches

TARGET_S = 1.0
"""Every entry point at its cap must run in under this many seconds."""


def _fresh_keys(d: qshape.Description) -> Callable[[], object]:
    """Canonical keys of ``d`` with the key caches cleared first (a cold lookup)."""

    def run() -> object:
        clear_key_caches()
        return qshape.canonical_keys(d)

    return run


def _timed(fn: Callable[[], Any], repeat: int = 3) -> tuple[float, str]:
    """Best wall time [s] of ``repeat`` calls, and the outcome (result type or error class)."""
    best = math.inf
    outcome = ""
    for _ in range(repeat):
        t0 = time.perf_counter()
        try:
            r = fn()
            outcome = type(r).__name__
        except qshape.QShapeError as exc:
            outcome = type(exc).__name__
        except Exception as exc:  # noqa: BLE001 (a leak is reported, not raised)
            outcome = f"LEAK {type(exc).__name__}"
        best = min(best, time.perf_counter() - t0)
    return best, outcome


def star(n: int, r_out: float = 40.0, r_in: float = 30.0, centre: float = 0.0) -> np.ndarray:
    """A simple, non-convex star polygon of n vertices (n even), shape (n, 2) [mm]."""
    t = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    r = np.where(np.arange(n) % 2 == 0, r_out, r_in)
    return np.stack([r * np.cos(t), r * np.sin(t)], axis=1) + centre


def wobbly_outline(n: int, radius: float = 200.0) -> np.ndarray:
    """A dense closed outline of n points (a noisy circle), shape (n, 2) [px]."""
    rng = np.random.default_rng(0)
    t = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    r = radius + rng.normal(0.0, 0.3, n)
    return np.stack([r * np.cos(t), r * np.sin(t)], axis=1) + 500.0


_Case = tuple[str, str, Callable[[], Any], str]
"""One case: entry, input size, the call, the expected outcome (a type name)."""


def _figure_cases(lim: Any, n: int) -> list[_Case]:
    """Figures at and past the point and hole caps."""
    holes = [
        star(8, 1.0, 0.7, 0.0) + [12.0 * math.cos(a), 12.0 * math.sin(a)]
        for a in np.linspace(0.0, 2 * math.pi, lim.max_holes, endpoint=False)
    ]
    disc = qshape.Figure.regular_polygon(64, 20.0).points
    return [
        (
            "Figure.from_polygon, star",
            f"{n} points",
            lambda: qshape.Figure.from_polygon(star(n)),
            "Figure",
        ),
        (
            "Figure.from_polygon, star",
            f"{n + 2} points",
            lambda: qshape.Figure.from_polygon(star(n + 2)),
            "FigureLimitError",
        ),
        (
            "Figure.from_polygon, 10^6-gon",
            "10^6 points",
            lambda: qshape.Figure.from_polygon(star(1_000_000)),
            "FigureLimitError",
        ),
        (
            "Figure with holes",
            f"{lim.max_holes} holes",
            lambda: qshape.Figure.from_polygon(disc, holes),
            "Figure",
        ),
        (
            "Figure with holes",
            f"{lim.max_holes + 1} holes",
            lambda: qshape.Figure.from_polygon(disc, [*holes, holes[0] * 0.1]),
            "FigureLimitError",
        ),
    ]


def _query_cases(lim: Any, n: int) -> list[_Case]:
    """Describe, match, keys, assign and parse at the caps, and parse of hostile text."""
    at_cap = qshape.Figure.from_polygon(star(n))
    d_cap = qshape.describe(at_cap)
    text = str(d_cap)
    d_small = qshape.describe(qshape.Figure.rectangle(40.0, 20.0))
    small = str(d_small)
    return [
        ("describe", f"{n} points", lambda: qshape.describe(at_cap), "Description"),
        ("match (self)", f"{n} points", lambda: qshape.match(d_cap, d_cap), "Match"),
        (
            "canonical_keys",
            f"{n} points",
            _fresh_keys(d_cap),
            "frozenset",
        ),
        ("assign 1 x 1", f"{n} points", lambda: qshape.assign([d_cap], [d_cap]), "list"),
        ("parse", f"{len(text)} chars, {n} nodes", lambda: qshape.parse(text), "Description"),
        (
            "parse, 10,000 nodes",
            "10000 nodes",
            lambda: qshape.parse(small.replace("nodes: 4", "nodes: 10000")),
            "TextLimitError",
        ),
        (
            "parse",
            f"{lim.max_text_chars + 1} chars",
            lambda: qshape.parse(small + " " * lim.max_text_chars),
            "TextLimitError",
        ),
        (
            "parse, node count of 5,000 digits",
            "5000 digits",
            lambda: qshape.parse(small.replace("nodes: 4", "nodes: " + "9" * 5000)),
            "ParseError",
        ),
        (
            "parse, area of 10,000 digits",
            "10000 digits",
            lambda: qshape.parse(small.replace("area: ", "area: " + "1" * 10_000, 1)),
            "ParseError",
        ),
        (
            "parse, 10,000 spaces in a node",
            "10000 spaces",
            lambda: qshape.parse(small.replace("@ (", "@" + " " * 10_000 + "(")),
            "Description",
        ),
        (
            "parse, 10^5 digits in a coordinate",
            "100000 digits",
            lambda: qshape.parse(small.replace("@ (", "@ (" + "1" * 100_000 + "x", 1)),
            "ParseError",
        ),
    ]


def _outline_cases(lim: Any) -> list[_Case]:
    """Dense outlines at and past their cap, and a square far from the origin."""
    dense = lim.max_dense_points
    square = np.array([[0.0, 0.0], [40.0, 0.0], [40.0, 40.0], [0.0, 40.0]])
    return [
        (
            "Figure.from_outline",
            f"{dense} dense points",
            lambda: qshape.Figure.from_outline(wobbly_outline(dense)),
            "Figure",
        ),
        (
            "Figure.from_outline",
            f"{dense + 1} dense points",
            lambda: qshape.Figure.from_outline(wobbly_outline(dense + 1)),
            "FigureLimitError",
        ),
        (
            "square 40 mm at 1e9",
            "offset 1e9",
            lambda: qshape.Figure.from_polygon(square + 1e9),
            "Figure",
        ),
        (
            "square 40 mm at 1e11",
            "offset 1e11",
            lambda: qshape.Figure.from_polygon(square + 1e11),
            "Figure",
        ),
        (
            "square 40 mm at 1e14",
            "offset 1e14",
            lambda: qshape.Figure.from_polygon(square + 1e14),
            "FigureLimitError",
        ),
    ]


def run() -> list[dict[str, Any]]:
    """Every case: name, cap, seconds, outcome, expected outcome, pass."""
    lim = default_limits()
    n = lim.max_points - lim.max_points % 2
    cases = [*_figure_cases(lim, n), *_query_cases(lim, n), *_outline_cases(lim)]
    square = np.array([[0.0, 0.0], [40.0, 0.0], [40.0, 40.0], [0.0, 40.0]])
    rows = []
    for name, size, fn, expected in cases:
        seconds, outcome = _timed(fn)
        rows.append(
            {
                "entry": name,
                "input": size,
                "seconds": seconds,
                "outcome": outcome,
                "expected": expected,
                "pass": outcome == expected and seconds < TARGET_S,
            }
        )
    far = qshape.Figure.from_polygon(square + 1e11)
    rows.append(
        {
            "entry": "area of the 40 mm square at 1e11",
            "input": "offset 1e11",
            "seconds": 0.0,
            "outcome": f"{far.area:g}",
            "expected": "1600",
            "pass": far.area == 1600.0,
        }
    )
    return rows


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Run the benchmark; print the table and write the JSON file."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("out/bench_robustness.json"))
    args = ap.parse_args(argv)
    rows = run()
    width = max(len(r["entry"]) for r in rows)
    for r in rows:
        flag = "PASS" if r["pass"] else "FAIL"
        print(
            f"{r['entry']:<{width}}  {r['input']:<24} {r['seconds'] * 1e3:9.1f} ms  "
            f"{r['outcome']:<18} {flag}"
        )
    worst = max(r["seconds"] for r in rows)
    out = {"rows": rows, "worst_seconds": worst, "all_pass": all(r["pass"] for r in rows)}
    print(f"slowest entry point: {worst * 1e3:.1f} ms (target < {TARGET_S * 1e3:.0f} ms)")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_text(args.out, json.dumps(out, indent=2) + "\n")
    return out


if __name__ == "__main__":
    run_cli(main)
