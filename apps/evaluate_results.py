"""What an evaluation produces: episode results, one row per policy, the table and its files.

`apps.evaluate` plays the episodes; this module holds their records (`EpisodeResult`,
`PolicyRow`, the `Protocol` they were played under), the protocol's metrics of an episode
(`agents.protocol.EpisodeMetrics`), the aggregation into a row, and the outputs: the printed
Markdown table (`COLUMNS`), ``eval.json``, ``eval.md`` and the bar chart ``eval.png``.
"""

from __future__ import annotations

import json
import math
import os
import platform
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from agents.protocol import EpisodeMetrics
from configs.files import atomic_path, write_json, write_text
from envs.task import tiles_per_minute

COLUMNS = (
    ("policy", "policy", "{}"),
    ("success_rate", "success", "{:.0%}"),
    ("filled", "slots filled", "{:.0%}"),
    ("correct", "correct/ep", "{:.2f}"),
    ("slots", "slots", "{:.0f}"),
    ("misplaced", "misplaced/ep", "{:.2f}"),
    ("dropped", "dropped/ep", "{:.2f}"),
    ("lost", "lost/ep", "{:.2f}"),
    ("stranded", "stranded/ep", "{:.2f}"),
    ("left", "left/ep", "{:.2f}"),
    ("tiles_per_min", "tiles/min (sim)", "{:.1f}"),
    ("wall_s_per_tile", "wall s/tile", "{:.3f}"),
)
"""(key, header, format) of the printed table."""


def env_key(env_kwargs: dict[str, Any]) -> str:
    """The env overrides as one canonical string (sorted keys): what an episode ran with."""
    return json.dumps(env_kwargs, sort_keys=True, default=str)


@dataclass(frozen=True)
class EpisodeResult:
    """One episode of one policy.

    Attributes:
        policy: Policy label.
        seed: Reset seed.
        design: Design played.
        success: Every slot filled correctly.
        correct: Slots filled correctly.
        slots: Slots of the design.
        misplaced: Real tiles on the mesh filling no slot.
        dropped: Drop events (the pad lost a tile in transit).
        lost: Tiles lost off the input belt.
        stranded: Real tiles out of every other state (beside the mesh, tilted).
        left: Real tiles never placed (on the input belt, held or waiting at the end).
        steps: Env steps.
        sim_s: Simulated time [s].
        span_s: Time the throughput is measured over [s] (to completion, or the horizon).
        wall_s: Wall time of the policy and the env steps (reset excluded) [s].
        episode_return: Sum of rewards.
        env: The env overrides the episode ran with (`env_key`); a resumed evaluation takes
            an episode from its log only when they are the same ("": unknown, never taken).
    """

    policy: str
    seed: int
    design: str
    success: bool
    correct: int
    slots: int
    misplaced: int
    dropped: int
    lost: int
    stranded: int
    steps: int
    sim_s: float
    span_s: float
    wall_s: float
    episode_return: float
    left: int = 0
    env: str = ""

    @property
    def tiles_per_min(self) -> float:
        """Correct tiles per simulated minute over ``span_s`` (`envs.task.tiles_per_minute`)."""
        return tiles_per_minute(self.correct, self.span_s)


@dataclass(frozen=True)
class PolicyRow:
    """Aggregate of one policy over the seeds (one table row).

    Attributes:
        policy: Label.
        episodes: Episodes played.
        success_rate: Fraction of successful episodes.
        filled: Mean fraction of slots filled correctly.
        correct: Mean slots filled correctly per episode.
        slots: Mean slots per episode.
        misplaced: Mean misplaced tiles per episode.
        dropped: Mean drop events per episode.
        lost: Mean lost tiles per episode.
        stranded: Mean stranded tiles per episode.
        left: Mean tiles never placed per episode.
        tiles_per_min: Mean over the episodes of their correct tiles per simulated minute
            (each measured to completion or over the horizon; `agents.protocol`).
        wall_s_per_tile: Wall seconds per correct tile over all episodes (None: no tile).
        mean_return: Mean episode return.
        mean_steps: Mean episode length [steps].
        env: Env overrides the policy ran with.
    """

    policy: str
    episodes: int
    success_rate: float
    filled: float
    correct: float
    slots: float
    misplaced: float
    dropped: float
    lost: float
    stranded: float
    left: float
    tiles_per_min: float
    wall_s_per_tile: float | None
    mean_return: float
    mean_steps: float
    env: dict[str, Any]


@dataclass(frozen=True)
class Protocol:
    """Where and how long policies are evaluated.

    Attributes:
        seeds: Reset seeds (the same for every policy).
        designs: Designs, episodes alternating over them (empty: the base env's).
        max_steps: Step limit per episode; 0: `apps.evaluate.STEPS_PER_SLOT` x slots.
        horizon_s: Throughput horizon of a failed episode [s]; 0:
            `apps.evaluate.HORIZON_S_PER_SLOT` x slots.
    """

    seeds: tuple[int, ...]
    designs: tuple[str, ...] = ()
    max_steps: int = 0
    horizon_s: float = 0.0


def episode_metrics(ep: EpisodeResult) -> EpisodeMetrics:
    """The protocol's metrics of an episode result (`agents.protocol.EpisodeMetrics`)."""
    return EpisodeMetrics.from_counts(
        ep, left=ep.left, tiles_per_min=ep.tiles_per_min, sim_s=ep.sim_s, span_s=ep.span_s
    )


def aggregate(label: str, episodes: Sequence[EpisodeResult], env: dict[str, Any]) -> PolicyRow:
    """One table row from a policy's episodes."""
    n = max(len(episodes), 1)
    correct = sum(e.correct for e in episodes)
    wall = sum(e.wall_s for e in episodes)

    metrics = [episode_metrics(e) for e in episodes]

    def mean(key: str) -> float:
        return sum(float(getattr(e, key)) for e in episodes) / n

    def protocol(key: str) -> float:
        return sum(float(getattr(m, key)) for m in metrics) / n

    return PolicyRow(
        policy=label,
        episodes=len(episodes),
        success_rate=protocol("success"),
        filled=protocol("filled"),
        correct=correct / n,
        slots=mean("slots"),
        misplaced=protocol("misplaced"),
        dropped=protocol("dropped"),
        lost=protocol("lost"),
        stranded=protocol("stranded"),
        left=protocol("left"),
        tiles_per_min=protocol("tiles_per_min"),
        wall_s_per_tile=wall / correct if correct else None,
        mean_return=mean("episode_return"),
        mean_steps=mean("steps"),
        env=env,
    )


def _fmt(value: Any, spec: str) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    return spec.format(value)


def markdown_table(rows: Sequence[PolicyRow]) -> str:
    """The rows as a Markdown table (`COLUMNS`)."""
    head = "| " + " | ".join(h for _, h, _ in COLUMNS) + " |"
    sep = "|" + "|".join("---" for _ in COLUMNS) + "|"
    body = ["| " + " | ".join(_fmt(getattr(r, k), f) for k, _, f in COLUMNS) + " |" for r in rows]
    return "\n".join([head, sep, *body])


def plot(rows: Sequence[PolicyRow], path: Path) -> None:
    """Bar charts of success rate, slots filled and tiles/min per policy (matplotlib PNG)."""
    import matplotlib as mpl  # noqa: PLC0415

    mpl.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    labels = [r.policy for r in rows]
    panels = (
        ("success rate", [r.success_rate for r in rows]),
        ("slots filled", [r.filled for r in rows]),
        ("tiles / min (simulated)", [r.tiles_per_min for r in rows]),
    )
    height = 1.2 + 0.45 * len(labels)
    fig, axes = plt.subplots(1, len(panels), figsize=(5 * len(panels), height), sharey=True)
    colors = [f"C{i % 10}" for i in range(len(labels))]
    for ax, (title, values) in zip(axes, panels, strict=True):
        ax.barh(labels, values, color=colors)
        ax.set_title(title)
        ax.invert_yaxis()
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=100)
    plt.close(fig)


def write_outputs(
    rows: Sequence[PolicyRow],
    episodes: dict[str, list[EpisodeResult]],
    seeds: Sequence[int],
    out: Path,
    extra: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Write ``eval.json``, ``eval.md`` and ``eval.png`` under ``out``; return the JSON dict."""
    out.mkdir(parents=True, exist_ok=True)
    report = {
        "date": datetime.now(UTC).isoformat(timespec="seconds"),
        "machine": {
            "node": platform.node(),
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
        },
        "seeds": list(seeds),
        "columns": [k for k, _, _ in COLUMNS],
        "rows": [asdict(r) for r in rows],
        "episodes": {k: [asdict(e) for e in v] for k, v in episodes.items()},
        **(extra or {}),
    }
    write_json(out / "eval.json", report)
    seed_text = f"{seeds[0]}-{seeds[-1]}" if len(seeds) > 1 else str(seeds[0])
    md = (
        f"Evaluation on {len(seeds)} seeds ({seed_text}), {report['date']}\n\n"
        + markdown_table(rows)
        + "\n"
    )
    write_text(out / "eval.md", md)
    plot(rows, out / "eval.png")
    return report


__all__ = [
    "COLUMNS",
    "EpisodeResult",
    "PolicyRow",
    "Protocol",
    "aggregate",
    "episode_metrics",
    "markdown_table",
    "plot",
    "write_outputs",
]
