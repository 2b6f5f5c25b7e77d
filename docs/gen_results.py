r"""Results at a glance: the one results file the task cards and the README quote.

``docs/results.json`` holds, per rung, the scripted, random and best learned policy on the
rung's held-out seeds: slots filled, success, tiles/min, the command that measures the row, how
long that command took, the date and where the figure comes from. A row is either measured by
this command (``source``: ``docs/gen_results.py``) or copied from a dated docs page that
measured it (``source`` names the page and its table); a copied row says so and keeps its page's
date.

Run from the repository root::

    python docs/gen_results.py evaluate --task MosaicDecision6-v1 \\
        --policies random checkpoints/MosaicDecision6-v0/PairBC_state/seed_0/bc.pt
    python docs/gen_results.py show                # the file as a table

``evaluate`` plays each policy on the task's protocol (`apps.evaluate`: held-out seeds and
designs, episode limit, horizon), one policy at a time so each row has its own time, and
replaces that (task, policy) row of the file. Regenerate the cards afterwards
(``python docs/gen_tasks.py --pages-only``).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from dataclasses import asdict, dataclass, fields
from datetime import UTC, datetime
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
RESULTS = DOCS / "results.json"
"""The results file."""
KINDS = ("scripted", "random", "learned", "reference")
"""What a row's policy is (``reference``: a non-learned policy other than the scripted one)."""
MEASURED_HERE = "docs/gen_results.py"
"""``source`` of a row this command measured."""


@dataclass(frozen=True)
class ResultRow:
    """One policy on one rung's held-out seeds.

    Attributes:
        task: Registered id evaluated (its version included).
        kind: One of `KINDS`.
        policy: What acted, in words.
        runs: Training seeds aggregated (IQM over runs when > 1), 1 otherwise.
        episodes: Held-out episodes per run.
        filled: Fraction of slots filled correctly (mean over episodes).
        success: Fraction of episodes with every slot filled.
        tiles_per_min: Correct tiles per simulated minute, or None when not measured.
        command: The command that measures the row.
        time: How long that command took, in words (with what it includes).
        date: Day of the measurement (YYYY-MM-DD).
        source: ``docs/gen_results.py`` or the docs page (and table) the row is copied from.
    """

    task: str
    kind: str
    policy: str
    runs: int
    episodes: int
    filled: float
    success: float
    tiles_per_min: float | None
    command: str
    time: str
    date: str
    source: str

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"{self.task}: kind {self.kind!r} is none of {KINDS}")


def load_results(path: Path = RESULTS) -> list[ResultRow]:
    """The rows of the results file, in file order.

    Raises:
        ValueError: A row with unknown or missing keys (names them) or an unknown kind.
    """
    data = json.loads(path.read_text(encoding="utf-8"))
    names = {f.name for f in fields(ResultRow)}
    rows = []
    for i, raw in enumerate(data["rows"]):
        if set(raw) != names:
            raise ValueError(
                f"{path.name} row {i}: keys {sorted(set(raw) ^ names)} differ from {sorted(names)}"
            )
        rows.append(ResultRow(**raw))
    return rows


def rung_name(env_id: str) -> str:
    """An id without its version (``MosaicDecision6-v1`` -> ``MosaicDecision6``)."""
    return env_id.rpartition("-")[0]


def rows_for(env_id: str, rows: list[ResultRow] | None = None) -> list[ResultRow]:
    """The rows of an id's rung (any version), scripted, random, learned, reference."""
    rows = load_results() if rows is None else rows
    mine = [r for r in rows if rung_name(r.task) == rung_name(env_id)]
    return sorted(mine, key=lambda r: KINDS.index(r.kind))


def save_results(rows: list[ResultRow], path: Path = RESULTS) -> None:
    """Write the file (rows grouped by rung in ladder order as given)."""
    text = json.dumps({"rows": [asdict(r) for r in rows]}, indent=1) + "\n"
    path.write_text(text, encoding="utf-8")


SCRIPTED = (
    "scripted",
    "agents.experts.cartesian:LowLevelExpert",
    "agents.experts.joint:LowLevelJointExpert",
)
"""Policy names of the scripted kind: the scripted cell and the scripted low-level controllers."""


def _kind(policy: str) -> str:
    if policy.partition("@")[0] in SCRIPTED:
        return "scripted"
    if policy.partition("@")[0] == "random":
        return "random"
    return "learned" if policy.partition("@")[0].endswith((".pt", ".zip")) else "reference"


def evaluate(task: str, policy: str, label: str = "") -> ResultRow:
    """Measure one policy on ``task``'s protocol with `apps.evaluate` (timed)."""
    if str(ROOT) not in sys.path:
        sys.path.insert(0, str(ROOT))
    from apps.evaluate import main as evaluate_main  # noqa: PLC0415

    command = f"python -m apps.evaluate --task {task} --policies {policy}"
    with tempfile.TemporaryDirectory() as out:
        wall, cpu = time.perf_counter(), time.process_time()
        report = evaluate_main(["--task", task, "--policies", policy, "--out", out, "--quiet"])
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    row = report["rows"][0]
    load = os.getloadavg()[0]
    cores = len(os.sched_getaffinity(0))
    return ResultRow(
        task=task,
        kind=_kind(policy),
        policy=label or row["policy"],
        runs=1,
        episodes=int(row["episodes"]),
        filled=round(float(row["filled"]), 3),
        success=round(float(row["success_rate"]), 3),
        tiles_per_min=round(float(row["tiles_per_min"]), 1),
        command=command,
        time=f"{cpu:.0f} CPU s ({wall:.0f} s wall at load {load:.1f}, {cores} of "
        f"{os.cpu_count()} cores)",
        date=datetime.now(UTC).date().isoformat(),
        source=MEASURED_HERE,
    )


def table(rows: list[ResultRow]) -> str:
    """The rows as a Markdown table."""
    lines = [
        "| task | policy | filled | success | tiles/min | time | date | source |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        tpm = "-" if r.tiles_per_min is None else f"{r.tiles_per_min:g}"
        lines.append(
            f"| {r.task} | {r.policy} | {r.filled:.2f} | {r.success:.2f} | {tpm} | {r.time} | "
            f"{r.date} | {r.source} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Command line (see the module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    ev = sub.add_parser("evaluate", help="measure policies and replace their rows")
    ev.add_argument("--task", required=True)
    ev.add_argument("--policies", nargs="+", required=True)
    ev.add_argument("--labels", nargs="*", default=[], help="row labels, one per policy")
    sub.add_parser("show", help="print the file as a table")
    args = ap.parse_args(argv)
    rows = load_results()
    if args.cmd == "show":
        print(table(rows))
        return 0
    labels = list(args.labels) + [""] * (len(args.policies) - len(args.labels))
    for policy, label in zip(args.policies, labels, strict=True):
        new = evaluate(args.task, policy, label)
        rows = load_results()  # as it is now: another run may have written it meanwhile
        key = (rung_name(new.task), new.kind, new.policy)
        at = [i for i, r in enumerate(rows) if (rung_name(r.task), r.kind, r.policy) == key]
        if at:
            rows[at[0]] = new
        else:
            rows.append(new)
        save_results(rows)
        print(table([new]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
