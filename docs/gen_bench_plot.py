"""Generate the benchmarks page's plot from the committed benchmark JSON files.

Left: every figure of ``docs/bench.json`` with a ``>=`` or ``<=`` target, as its headroom over
the target (value / target for ``>=``, target / value for ``<=``: above 1 the target is met),
on a log scale; figures that scale with the machine's speed and load (`bench_page.portable`)
are drawn hatched, since their headroom says as much about the load as about the code. Right:
the ratios measured within one run, which hold across machines: the three of
``docs/bench_env_ratios.json`` and the planner's cycle over its time-optimal bound and the
extraction over ``cv2.Canny`` from ``docs/bench.json``, each beside its target. The run's load
(start and end) is in the title. A separate command (not part of the docs build)::

    python docs/gen_bench_plot.py      # writes docs/img/bench_overview.png
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
for p in (ROOT, DOCS):
    if str(p) not in sys.path:
        sys.path.insert(0, str(p))

from bench_page import BENCH_JSON, RATIO_FIGURES, RATIOS_JSON, load_text, portable  # noqa: E402

from benchmarks.figures import Figure  # noqa: E402

OUT_PNG = DOCS / "img" / "bench_overview.png"
"""The committed plot."""
RUN_RATIOS = (
    ("planner", "cycle / lower bound (dwells included)", "cycle / time-optimal bound"),
    ("vision", "extract 656x492 / cv2.Canny", "extraction / cv2.Canny"),
)
"""Ratios of the benchmark's table shown beside the env ratios: (group, figure, label)."""
LABEL_CHARS = 62
"""Longest figure name on the axis [characters]."""
MAX_BYTES = 1_000_000
"""Size limit of the committed plot [bytes]."""


def headroom(f: Figure) -> float | None:
    """Value over target (``>=``) or target over value (``<=``); None without either."""
    op, _, num = f.target.partition(" ")
    if f.value is None or op not in (">=", "<=", ">", "<"):
        return None
    target = float(num)
    if op.startswith(">"):
        return f.value / target if target else None
    return target / f.value if f.value else None


def ratio_rows(report: dict[str, Any], ratios: dict[str, Any]) -> list[tuple[str, float, float]]:
    """(label, ratio, target) of the run-internal ratios (lower is better for each)."""
    rows = []
    for name, r in ratios["ratios"].items():
        top, bottom = RATIO_FIGURES.get(name, (name, "baseline"))
        rows.append((f"{top} /\n{bottom}", float(r["ratio"]), float(r["target"])))
    figures = {(f["group"], f["name"]): f for f in report["figures"]}
    for group, name, label in RUN_RATIOS:
        f = figures.get((group, name))
        if f and f["value"] is not None and f["target"]:
            rows.append((label, float(f["value"]), float(f["target"].split()[-1])))
    return rows


def _label(f: Figure) -> str:
    """A figure's axis label: group, name (shortened), target."""
    name = f.name if len(f.name) <= LABEL_CHARS else f.name[: LABEL_CHARS - 3] + "..."
    return f"{f.group}: {name} ({f.target})"


def plot(report: dict[str, Any], ratios: dict[str, Any], path: Path) -> Path:
    """Draw and save the two panels; returns ``path``."""
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    figs = [Figure(**f) for f in report["figures"]]
    rows = [(f, h) for f in figs if (h := headroom(f)) is not None]
    exact = [f for f in figs if f.passed is not None and headroom(f) is None]
    fig, (ax, bx) = plt.subplots(
        1, 2, figsize=(13.5, 0.24 * len(rows) + 2.2), gridspec_kw={"width_ratios": [1.6, 1]}
    )
    y = range(len(rows))
    for i, (f, h) in enumerate(rows):
        color = "#3a9d5d" if f.passed else "#d0453a"
        ax.barh(
            i,
            h,
            color=color if portable(f) else "white",
            edgecolor=color,
            hatch=None if portable(f) else "////",
        )
    ax.set_yticks(list(y), [_label(f) for f, _ in rows], fontsize=6.5)
    ax.invert_yaxis()
    ax.set_xscale("log")
    ax.axvline(1.0, color="black", lw=1)
    ax.set_xlabel("headroom over the target (> 1: met); hatched: depends on the machine's speed")
    n_met = sum(bool(f.passed) for f in exact)
    ax.set_title(
        f"{report['summary']['passed']} of {report['summary']['with_target']} targets met; "
        f"exact targets (accuracy, 0 misplaced) {n_met} of {len(exact)} (not drawn)",
        fontsize=9,
    )
    rr = ratio_rows(report, ratios)
    for i, (_, r, t) in enumerate(rr):
        bx.barh(i, r, height=0.5, color="#3a9d5d" if r <= t else "#d0453a")
        bx.plot([t, t], [i - 0.4, i + 0.4], color="black", lw=2)
        bx.text(r, i, f" {r:.2f}", va="center", fontsize=8)
    bx.set_yticks(range(len(rr)), [label for label, _, _ in rr], fontsize=8)
    bx.invert_yaxis()
    bx.set_xscale("log")
    bx.set_xlabel("ratio (black tick: target, at most)")
    bx.set_title("ratios within one run: hold across machines", fontsize=9)
    fig.suptitle(
        f"Benchmark run {report['date'][:16].replace('T', ' ')} UTC ({report['mode']}), "
        f"{load_text(report['machine'])}; env ratios {ratios.get('date', '?')}",
        fontsize=9,
    )
    fig.subplots_adjust(left=0.3, right=0.98, bottom=0.06, top=0.93, wspace=0.75)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=90)
    plt.close(fig)
    if path.stat().st_size > MAX_BYTES:
        raise SystemExit(f"error: {path} is {path.stat().st_size} bytes, over {MAX_BYTES}")
    return path


def main(argv: list[str] | None = None) -> None:
    """Command line (see the module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bench", type=Path, default=BENCH_JSON)
    ap.add_argument("--ratios", type=Path, default=RATIOS_JSON)
    ap.add_argument("--out", type=Path, default=OUT_PNG)
    args = ap.parse_args(argv)
    report = json.loads(args.bench.read_text(encoding="utf-8"))
    ratios = json.loads(args.ratios.read_text(encoding="utf-8"))
    out = plot(report, ratios, args.out)
    print(f"wrote {out} ({out.stat().st_size // 1000} kB)")


if __name__ == "__main__":
    main()
