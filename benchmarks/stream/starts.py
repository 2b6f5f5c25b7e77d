"""Which starts of the stream can be saved at all: the tiles given at reset, the fastest cycle.

Run ``python -m benchmarks.stream.starts``. For every rung of ``configs/bench_stream_starts.yaml``
it resets the env on each seed (no episode is played) and asks whether any order of the first
two picks saves every tile given at reset: a pick saves a tile when its contact comes before the
belt carries the tile past the pick area's downstream edge, and even the fastest pick cycle the
planner was measured to make (first contact ``first_contact_s`` after reset, the second
``second_contact_s``) leaves some starts where no order does (earliest deadline first,
`agents.scripted.belt_schedule.deadline_order`, saves every tile whenever any order does). It
also counts the starts the scripted cell's own scheduler, with its times taken on the long side
(`configs/belt_schedule.yaml`), expects to lose. Prints a table and writes
``out/bench_stream_starts.json``.

Such a start is one no policy of the rung can be expected to solve: with one pad, a pick that
keeps its contacts inside the pick area loses a tile whatever it decides (a contact a little
past the pick area's edge sometimes still catches a tile: the bound is the pick area's, not the
belt end's).
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from apps.cli import CommandParser, run_cli
from configs import ConfigError, load_config
from configs.checks import check_fields, checked
from configs.files import write_text

OUT = Path("out/bench_stream_starts.json")
"""Default output file."""


@dataclass(frozen=True)
class StreamStartsConfig:
    """``configs/bench_stream_starts.yaml``.

    Attributes:
        tasks: Stream rungs whose starts are counted (each with a moving belt).
        seeds: First and last reset seed [count].
        first_contact_s: Reset to the first pick's contact, the fastest measured [s].
        second_contact_s: Reset to the second pick's contact, the fastest measured [s].
    """

    tasks: tuple[str, ...] = ("MosaicStream-v1", "MosaicStream-v2")
    seeds: tuple[int, int] = checked((10000, 10624), length=2, ge=0)
    first_contact_s: float = checked(0.65, gt=0)
    second_contact_s: float = checked(2.67, gt=0)

    def __post_init__(self) -> None:
        """Raise `ConfigError` on bad values."""
        check_fields(self, ConfigError, prefix="bench_stream_starts: ")
        if not self.tasks:
            raise ConfigError("bench_stream_starts: tasks must not be empty")
        if self.seeds[0] > self.seeds[1]:
            raise ConfigError(f"bench_stream_starts: seeds {self.seeds} must be first <= last")
        if self.second_contact_s <= self.first_contact_s:
            raise ConfigError(
                f"bench_stream_starts: second_contact_s {self.second_contact_s} s must come "
                f"after first_contact_s {self.first_contact_s} s"
            )


@dataclass(frozen=True)
class StartCount:
    """The starts of one rung.

    Attributes:
        task: The rung.
        resets: Resets looked at.
        lost_at_fastest: Starts where no order of picks saves every tile, even at the fastest
            measured cycle.
        lost_by_schedule: Starts where the scheduler's rule, with its long-side times, expects
            to lose a tile.
        downstream_x: The most downstream starting tile's position along the belt over the
            resets, [lowest, median, highest] [m], from the pick area's downstream edge
            (negative: upstream of it).
        unsaved_seeds: The seeds of the ``lost_at_fastest`` starts.
    """

    task: str
    resets: int
    lost_at_fastest: int
    lost_by_schedule: int
    downstream_x: tuple[float, float, float]
    unsaved_seeds: tuple[int, ...]


def count_starts(cfg: StreamStartsConfig, task: str) -> StartCount:
    """Reset ``task`` on every seed of ``cfg`` and count the starts no order saves."""
    import gymnasium as gym  # noqa: PLC0415 - the simulation stack, only when run

    import envs  # noqa: F401, PLC0415 - registers the ladder
    from agents.experts.deadline import belt_timing  # noqa: PLC0415
    from agents.scripted.belt_config import load_belt_schedule_config  # noqa: PLC0415
    from agents.scripted.belt_schedule import deadline_order  # noqa: PLC0415

    sched = load_belt_schedule_config()
    env = gym.make(task)
    try:
        timing = belt_timing(env, sched)
        edge = timing.last_x + sched.end_margin  # the pick area's downstream edge
        cell = env.unwrapped.cell  # type: ignore[attr-defined]
        unsaved: list[int] = []
        by_schedule = 0
        front: list[float] = []
        first, last = cfg.seeds
        for seed in range(first, last + 1):
            env.reset(seed=seed)
            on_belt = cell.on_stage & cell.input_side()
            x = cell.data.xpos[cell.ids.tile_body][on_belt, 0]
            front.append(float(x.max()) - edge)
            fastest = deadline_order(
                x,
                timing.belt_speed,
                edge,
                cfg.first_contact_s,
                cfg.second_contact_s - cfg.first_contact_s,
            )
            if not fastest.saves_all:
                unsaved.append(seed)
            rule = deadline_order(
                x, timing.belt_speed, timing.last_x, sched.first_reach_s, sched.cycle_s
            )
            by_schedule += not rule.saves_all
    finally:
        env.close()
    lo, mid, hi = np.quantile(front, [0.0, 0.5, 1.0])
    return StartCount(
        task=task,
        resets=last - first + 1,
        lost_at_fastest=len(unsaved),
        lost_by_schedule=by_schedule,
        downstream_x=(float(lo), float(mid), float(hi)),
        unsaved_seeds=tuple(unsaved),
    )


def table(counts: list[StartCount]) -> str:
    """Markdown table of the counts."""
    head = (
        "| rung | resets | no order saves every tile (fastest cycle) | the scheduler's rule "
        "expects a loss | most downstream tile, m from the pick area's edge (min / median / "
        "max) |\n|---|---|---|---|---|"
    )
    rows = [
        f"| {c.task} | {c.resets} | {c.lost_at_fastest} ({c.lost_at_fastest / c.resets:.1%}) | "
        f"{c.lost_by_schedule} ({c.lost_by_schedule / c.resets:.1%}) | "
        + " / ".join(f"{v:+.3f}" for v in c.downstream_x)
        + " |"
        for c in counts
    ]
    return "\n".join([head, *rows])


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line (see the module docstring)."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="bench_stream_starts", help="bundled name or YAML path")
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args(argv)
    cfg = load_config(StreamStartsConfig, args.config)
    counts = [count_starts(cfg, task) for task in cfg.tasks]
    print(table(counts))
    report = {"config": asdict(cfg), "counts": [asdict(c) for c in counts]}
    write_text(args.out, json.dumps(report, indent=2))
    return report


if __name__ == "__main__":
    run_cli(main)
