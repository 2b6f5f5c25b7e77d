"""Stress curve of the stream: the highest supply rate the scripted cell sustains, no tile lost.

Run ``python -m benchmarks.stream.stress`` (``--figure`` also writes the figure,
``--tiles 20`` for a quick look, ``--from-json out/bench_stream_stress.json --figure`` to print
and plot an earlier run again). For every belt speed and supply period of
``configs/bench_stream_stress.yaml``, the scripted cell (`agents.scripted.agent.ScriptedAgent`,
its belt scheduler `agents.scripted.belt_schedule`) plays episodes of the task's env with that
stream until at least ``tiles`` tiles were fed. Per run it prints the supply rate, the rate the cell
sustained (correct tiles per simulated minute between its first and last placement of each
episode, pooled), the tiles fed, placed, lost off the belt's end and misplaced, the cell's mean
pick cycle and the rate that cycle bounds (60 / cycle). A run *keeps up* when every tile fed
was placed correctly; one that does not is reported as such, with its losses and the rate it
did sustain. Per speed: the highest supply rate kept up with. Writes
``out/bench_stream_stress.json``.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from typing import Any

from apps.cli import CommandParser, run_cli
from configs import ConfigError, load_config
from configs.checks import check_fields, checked
from configs.files import write_text

OUT = Path("out/bench_stream_stress.json")
"""Default output file."""
SECONDS_PER_MINUTE = 60.0


@dataclass(frozen=True)
class StreamStressConfig:
    """``configs/bench_stream_stress.yaml``.

    Attributes:
        task: The ladder rung whose env is stressed.
        periods: Supply periods, s between two streamed tiles [s].
        speeds: Input belt speeds [m/s].
        tiles: Tiles fed per (period, speed), at least.
        first_seed: Reset seed of a run's first episode (the k-th: ``first_seed + k``).
        stream_initial: Tiles on the belt at reset.
        image_size: Input camera image (height, width) [px].
        steps_per_tile: Episode step limit per tile of the design.
        figure: Path of the figure ``--figure`` writes.
    """

    task: str = "MosaicStream-v1"
    periods: tuple[float, ...] = checked((2.5, 2.2, 2.0, 1.8), gt=0)
    speeds: tuple[float, ...] = checked((0.1, 0.2), gt=0)
    tiles: int = checked(100, gt=0)
    first_seed: int = checked(2000, ge=0)
    stream_initial: int = checked(0, ge=0)
    image_size: tuple[int, int] = checked((492, 656), length=2, gt=0)
    steps_per_tile: int = checked(2, gt=0)
    figure: str = "docs/stream_stress.png"

    def __post_init__(self) -> None:
        """Raise `ConfigError` on bad values."""
        check_fields(self, ConfigError, prefix="bench_stream_stress: ")
        if not self.periods or not self.speeds:
            raise ConfigError("bench_stream_stress: periods and speeds must not be empty")


@dataclass(frozen=True)
class StressRun:
    """One (speed, period) run.

    Attributes:
        speed: Belt speed [m/s].
        period: Supply period [s].
        episodes: Episodes played.
        fed: Tiles fed.
        correct: Tiles placed correctly.
        lost: Tiles lost off the belt's end (or dropped in transit).
        misplaced: Tiles placed wrongly (or stranded beside the mesh).
        given_up: Tiles the scheduler gave up (no pick could reach them in time).
        supply_per_min: The supply rate, 60 / period [tiles/min].
        sustained_per_min: Correct tiles per simulated minute from each episode's first to
            its last placement, pooled [tiles/min].
        cycle_s: Mean simulated time of the cell's pick cycles [s] (NaN: no pick).
        cycle_bound_per_min: The rate that cycle allows, 60 / cycle_s [tiles/min] (NaN: no
            pick).
        wall_s: Wall time of the run [s].
    """

    speed: float
    period: float
    episodes: int
    fed: int
    correct: int
    lost: int
    misplaced: int
    given_up: int
    supply_per_min: float
    sustained_per_min: float
    cycle_s: float
    cycle_bound_per_min: float
    wall_s: float

    @property
    def keeps_up(self) -> bool:
        """Every tile fed was placed correctly."""
        return self.correct == self.fed and self.lost == 0 and self.misplaced == 0


def stress_run(
    cfg: StreamStressConfig, speed: float, period: float, env_kwargs: dict[str, Any]
) -> StressRun:
    """Play episodes of one stream until ``cfg.tiles`` tiles were fed (see the module doc)."""
    import gymnasium as gym  # noqa: PLC0415 - the simulation stack, only when run

    from agents.scripted.agent import ScriptedAgent  # noqa: PLC0415

    kwargs = {
        **env_kwargs,
        "action_mode": "pick_place",
        "obs_mode": "rgb",
        "image_size": list(cfg.image_size),
        "belt_speed": speed,
        "stream_period": period,
        "stream_initial": cfg.stream_initial,
    }
    t0 = time.perf_counter()
    env = gym.make("envs:MosaicAssembly-v0", max_episode_steps=None, **kwargs)
    try:
        agent = ScriptedAgent.from_env(env)
        fed = correct = lost = misplaced = given_up = episodes = 0
        span = 0.0
        spaced = 0
        picks: list[float] = []
        while fed < cfg.tiles:
            obs, info = env.reset(seed=cfg.first_seed + episodes)
            agent.reset()
            slots = len(env.unwrapped.task.slot_class)  # type: ignore[attr-defined]
            placed_at: list[float] = []
            for _ in range(cfg.steps_per_tile * slots):
                start = float(info.get("sim_time", 0.0))
                action, _ = agent.predict(obs)
                obs, _, terminated, truncated, info = env.step(action)
                if agent.last_command is not None:
                    picks.append(float(info["sim_time"]) - start)
                ev = info["evaluation"]
                placed_at += [float(info["sim_time"])] * (ev["correct"] - len(placed_at))
                if terminated or truncated:
                    break
            ev = info["evaluation"]
            episodes += 1
            fed += int(ev["fed"])
            correct += int(ev["correct"])
            lost += int(ev["lost_tiles"] + ev["dropped_tiles"])
            misplaced += int(ev["misplaced"] + ev["stranded"])
            if agent.belt is not None:
                given_up += agent.belt.tally().rejected
            if len(placed_at) > 1:
                span += placed_at[-1] - placed_at[0]
                spaced += len(placed_at) - 1
    finally:
        env.close()
    cycle = sum(picks) / len(picks) if picks else float("nan")
    return StressRun(
        speed=speed,
        period=period,
        episodes=episodes,
        fed=fed,
        correct=correct,
        lost=lost,
        misplaced=misplaced,
        given_up=given_up,
        supply_per_min=SECONDS_PER_MINUTE / period,
        sustained_per_min=SECONDS_PER_MINUTE * spaced / span if span > 0 else 0.0,
        cycle_s=cycle,
        cycle_bound_per_min=SECONDS_PER_MINUTE / cycle,
        wall_s=time.perf_counter() - t0,
    )


def highest_kept_up(runs: list[StressRun], speed: float) -> StressRun | None:
    """The run of ``speed`` with the highest supply rate the cell kept up with (None: none)."""
    kept = [r for r in runs if r.speed == speed and r.keeps_up]
    return max(kept, key=lambda r: r.supply_per_min) if kept else None


def table(runs: list[StressRun]) -> str:
    """The runs as a Markdown table, then one verdict line per speed."""
    lines = [
        "| belt m/s | period s | supply /min | sustained /min | fed | correct | lost | "
        "misplaced | given up | cycle s | cycle bound /min | verdict |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in runs:
        verdict = (
            "keeps up"
            if r.keeps_up
            else f"cannot keep up: {r.fed - r.correct} of {r.fed} tiles not placed"
        )
        lines.append(
            f"| {r.speed:.2f} | {r.period:.1f} | {r.supply_per_min:.1f} | "
            f"{r.sustained_per_min:.1f} | {r.fed} | {r.correct} | {r.lost} | {r.misplaced} | "
            f"{r.given_up} | {r.cycle_s:.2f} | {r.cycle_bound_per_min:.1f} | {verdict} |"
        )
    for speed in sorted({r.speed for r in runs}):
        best = highest_kept_up(runs, speed)
        lines.append(
            f"belt {speed:.2f} m/s: "
            + (
                f"highest supply kept up with {best.supply_per_min:.1f} tiles/min "
                f"(period {best.period:.1f} s)"
                if best is not None
                else "no supply rate tried is kept up with"
            )
        )
    return "\n".join(lines)


def plot(runs: list[StressRun], path: Path) -> None:
    """The stress curve: sustained against supply rate per belt speed, with the cycle bound."""
    import matplotlib  # noqa: PLC0415 - only for the figure

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    fig, ax = plt.subplots(figsize=(7.0, 4.6))
    supply = sorted({r.supply_per_min for r in runs})
    lo, hi = supply[0] - 2.0, supply[-1] + 2.0
    ax.plot([lo, hi], [lo, hi], color="0.6", lw=1, ls=":", label="sustained = supply")
    for k, speed in enumerate(sorted({r.speed for r in runs})):
        rs = sorted((r for r in runs if r.speed == speed), key=lambda r: r.supply_per_min)
        color = f"C{k}"
        ax.plot(
            [r.supply_per_min for r in rs],
            [r.sustained_per_min for r in rs],
            color=color,
            marker="o",
            label=f"belt {speed:.1f} m/s",
        )
        for r in rs:
            if not r.keeps_up:
                ax.plot(r.supply_per_min, r.sustained_per_min, "x", color="k", ms=9, mew=2)
                ax.annotate(
                    f"{r.fed - r.correct} not placed",
                    (r.supply_per_min, r.sustained_per_min),
                    textcoords="offset points",
                    xytext=(6, -12 - 10 * k),
                    fontsize=8,
                    color=color,
                )
        bounds = [r.cycle_bound_per_min for r in rs if math.isfinite(r.cycle_bound_per_min)]
        if bounds:
            bound = sum(bounds) / len(bounds)
            ax.axhline(bound, color=color, ls="--", lw=1, label=f"cycle bound {bound:.1f}/min")
    ax.set_xlim(lo, hi)
    ax.set_xlabel("supply [tiles per simulated minute]")
    ax.set_ylabel("placed correctly [tiles per simulated minute]")
    ax.set_title("Scripted cell on a stream (x: tiles lost, not kept up with)")
    ax.legend(fontsize=8, loc="upper left")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _finite(value: float) -> float | None:
    return value if math.isfinite(value) else None


def replot(path: Path, figure: bool) -> dict[str, Any]:
    """Print the table (and with ``figure`` write the figure) of an earlier run's JSON."""
    report: dict[str, Any] = json.loads(path.read_text(encoding="utf-8"))
    names = {f.name for f in fields(StressRun)}
    nan = float("nan")
    runs: list[StressRun] = []
    for r in report["runs"]:
        values: dict[str, Any] = {k: (nan if v is None else v) for k, v in r.items() if k in names}
        runs.append(StressRun(**values))
    print(table(runs))
    if figure:
        out = Path(report["config"]["figure"])
        plot(runs, out)
        print(f"wrote {out}")
    return report


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line (see the module docstring)."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="bench_stream_stress", help="bundled name or YAML path")
    ap.add_argument("--tiles", type=int, default=0, help="tiles per run (0: the config's)")
    ap.add_argument("--periods", type=float, nargs="+", default=None, help="s, supply periods")
    ap.add_argument("--speeds", type=float, nargs="+", default=None, help="m/s, belt speeds")
    ap.add_argument("--figure", action="store_true", help="also write the config's figure")
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument(
        "--from-json", type=Path, default=None, help="print and plot an earlier run's JSON"
    )
    args = ap.parse_args(argv)
    if args.from_json is not None:
        return replot(args.from_json, args.figure)
    cfg = load_config(StreamStressConfig, args.config)
    changes: dict[str, Any] = {}
    if args.tiles:
        changes["tiles"] = args.tiles
    if args.periods:
        changes["periods"] = tuple(args.periods)
    if args.speeds:
        changes["speeds"] = tuple(args.speeds)
    cfg = replace(cfg, **changes)
    from apps.evaluate import task_protocol  # noqa: PLC0415 - the task's env

    base, _ = task_protocol(cfg.task)
    runs = []
    for speed in cfg.speeds:
        for period in cfg.periods:
            run = stress_run(cfg, speed, period, base)
            runs.append(run)
            print(
                f"  belt {speed:.2f} m/s, period {period:.1f} s: {run.correct}/{run.fed} placed, "
                f"{run.lost} lost, {run.sustained_per_min:.1f} tiles/min, {run.wall_s:.0f} s",
                flush=True,
            )
    print(table(runs))
    report = {
        "config": asdict(cfg),
        "runs": [
            {
                **asdict(r),
                "cycle_s": _finite(r.cycle_s),
                "cycle_bound_per_min": _finite(r.cycle_bound_per_min),
                "keeps_up": r.keeps_up,
            }
            for r in runs
        ],
        "highest_kept_up": {
            str(s): (asdict(b) if (b := highest_kept_up(runs, s)) is not None else None)
            for s in cfg.speeds
        },
    }
    write_text(args.out, json.dumps(report, indent=2))
    if args.figure:
        plot(runs, Path(cfg.figure))
        print(f"wrote {cfg.figure}")
    print(f"wrote {args.out}")
    return report


if __name__ == "__main__":
    run_cli(main)
