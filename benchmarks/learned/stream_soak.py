r"""The moving belt's soak row: a policy on thousands of held-out stream episodes, losses counted.

Run::

    python -m benchmarks.learned.stream_soak --teacher        # at least 10,000 tiles, 2 workers
    python -m benchmarks.learned.stream_soak --tiles 320      # a short run
    python -m benchmarks.learned.stream_soak --policy scripted --out out/soak_scripted

The policy (default: the shipped stream clone,
``checkpoints/MosaicStream-v2/PairBC_stream/seed_0/bc.pt``; any `apps.evaluate` policy name)
plays ``--task`` (default ``MosaicStream-v2``) under the rung's own protocol (dynamic execution,
its step limit and throughput horizon) on consecutive seeds from ``--first-seed`` until at least
``--tiles`` tiles have been supplied. The default first seed, 10000, is disjoint from the
clone's training seeds (0-59) and from the rung's held-out seeds (1000-1019, 2000-2019). The
seeds are dealt out to ``--workers`` processes, each an `apps.evaluate` run in its own folder
under ``--out`` that appends every episode to its log as it finishes: a soak that was stopped
resumes where it stopped (with any number of workers), and no finished episode is played again.
A folder keeps one soak: another task or policy there is refused.

The tally (printed, and written to ``<out>/soak.json``): tiles supplied, placed correctly,
misplaced, dropped in transit, lost off the belt's end, stranded beside the mesh and left
unplaced; the share placed correctly with its 95 % Wilson interval; the share of episodes
completed; tiles per simulated minute against the supply rate; the wall time. With
``--teacher``, the teacher the clone was cloned from (`agents.experts.deadline.DeadlineExpert`:
the scheduler's rule on the env's ground truth) then plays every seed the policy failed, to
tell the losses its rule cannot avoid from the policy's own (its episodes are kept in
``<out>/teacher_*.jsonl``; a seed in any of them is not played again).
"""

from __future__ import annotations

import json
import math
import multiprocessing
import signal
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass
from functools import partial
from pathlib import Path
from typing import Any

from apps.cli import CommandParser, run_cli, write_result
from apps.evaluate_results import EpisodeResult

TASK = "MosaicStream-v2"
"""The rung soaked."""
POLICY = "checkpoints/MosaicStream-v2/PairBC_stream/seed_0/bc.pt"
"""The shipped stream clone."""
FIRST_SEED = 10_000
"""First soak seed: disjoint from the clone's training seeds and the rung's held-out seeds."""
LOG = "episodes.jsonl"
"""`apps.evaluate`'s per-episode log in each worker's folder."""
SETTINGS = "soak_settings.json"
"""The task and policy a soak folder belongs to."""
Z95 = 1.959964
"""Standard normal quantile of a two-sided 95 % interval."""


@dataclass(frozen=True)
class SoakTally:
    """The soak's totals over its episodes.

    Attributes:
        episodes: Episodes played.
        tiles: Tiles supplied (the design's slots, one tile each).
        correct: Tiles placed in their slot within tolerance.
        misplaced: Tiles on the mesh filling no slot.
        dropped: Drop events (the pad lost a tile in transit).
        lost: Tiles carried off the input belt's end.
        stranded: Tiles beside the mesh or tilted.
        left: Tiles never placed (still on the belt or held at the episode's end).
        correct_share: ``correct / tiles``.
        correct_low: Lower end of the share's 95 % Wilson interval.
        correct_high: Upper end of the share's 95 % Wilson interval.
        episodes_complete: Share of the episodes with every slot filled correctly.
        tiles_per_min: Mean over the episodes of correct tiles per simulated minute.
        supply_per_min: The stream's supply rate [tiles/min].
        wall_s: Wall seconds of the policy and the env steps, summed over the episodes.
    """

    episodes: int
    tiles: int
    correct: int
    misplaced: int
    dropped: int
    lost: int
    stranded: int
    left: int
    correct_share: float
    correct_low: float
    correct_high: float
    episodes_complete: float
    tiles_per_min: float
    supply_per_min: float
    wall_s: float


def wilson(successes: int, trials: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval of a binomial share (``(0, 1)`` without trials)."""
    if trials <= 0:
        return 0.0, 1.0
    p = successes / trials
    denom = 1.0 + z * z / trials
    centre = (p + z * z / (2 * trials)) / denom
    half = z * math.sqrt(p * (1.0 - p) / trials + z * z / (4 * trials * trials)) / denom
    return max(0.0, centre - half), min(1.0, centre + half)


def tally(episodes: Sequence[EpisodeResult], supply_per_min: float) -> SoakTally:
    """The totals of ``episodes`` (see `SoakTally`)."""
    n = len(episodes)
    tiles = sum(e.slots for e in episodes)
    correct = sum(e.correct for e in episodes)
    low, high = wilson(correct, tiles)
    return SoakTally(
        episodes=n,
        tiles=tiles,
        correct=correct,
        misplaced=sum(e.misplaced for e in episodes),
        dropped=sum(e.dropped for e in episodes),
        lost=sum(e.lost for e in episodes),
        stranded=sum(e.stranded for e in episodes),
        left=sum(e.left for e in episodes),
        correct_share=correct / tiles if tiles else 0.0,
        correct_low=low,
        correct_high=high,
        episodes_complete=sum(e.success for e in episodes) / n if n else 0.0,
        tiles_per_min=sum(e.tiles_per_min for e in episodes) / n if n else 0.0,
        supply_per_min=supply_per_min,
        wall_s=sum(e.wall_s for e in episodes),
    )


def deal(seeds: Sequence[int], workers: int) -> list[list[int]]:
    """``seeds`` dealt round-robin to ``workers`` lists (equal shares, each in order)."""
    return [list(seeds[i::workers]) for i in range(workers) if seeds[i::workers]]


def in_workers(
    job: Callable[[list[int], str], None], seeds: Sequence[int], workers: int, out: Path, name: str
) -> None:
    """Run ``job`` on each part of ``deal(seeds, workers)``, each in a fresh (spawned) process.

    Part ``i`` gets ``out / name.format(i)`` as its output path. Spawned workers copy no GL or
    torch state. A stopped soak stops its workers too: on an exception, Ctrl-C or SIGTERM the
    workers are terminated (a worker left running would go on appending to a log the next
    soak resumes from, so its episodes would be counted twice).
    """
    spawn = multiprocessing.get_context("spawn")
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=spawn)
    main = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, _exit_on_term) if main else None
    try:
        jobs = [
            pool.submit(job, part, str(out / name.format(i)))
            for i, part in enumerate(deal(seeds, workers))
        ]
        for done in jobs:
            done.result()
    except BaseException:
        for child in multiprocessing.active_children():
            child.terminate()
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    finally:
        if main:
            signal.signal(signal.SIGTERM, previous)
    pool.shutdown()


def _exit_on_term(signum: int, _frame: Any) -> None:
    """SIGTERM as an exit that unwinds (so `in_workers` stops its workers)."""
    raise SystemExit(128 + signum)


def _play(task: str, policy: str, seeds: list[int], out: str) -> None:
    """One worker: `apps.evaluate` on ``seeds`` into ``out`` (resuming its log)."""
    from apps import evaluate  # noqa: PLC0415 - imported in the worker process

    spec = ",".join(str(s) for s in seeds)
    evaluate.main(["--task", task, "--policies", policy, "--seeds", spec, "--out", out, "--quiet"])


def read_episodes(out: Path) -> list[EpisodeResult]:
    """Every episode in the worker folders' logs under ``out``."""
    from configs.files import complete_lines  # noqa: PLC0415

    found = []
    for log in sorted(out.glob(f"worker_*/{LOG}")):
        found += [EpisodeResult(**json.loads(line)) for line in complete_lines(log)]
    return found


def _teacher(task: str, seeds: list[int], log: str) -> None:
    """One worker: the teacher on ``seeds``, each episode appended to ``log``."""
    import gymnasium as gym  # noqa: PLC0415

    import envs  # noqa: F401, PLC0415 - registers the ladder
    from agents.experts.deadline import DeadlineExpert  # noqa: PLC0415
    from configs.files import append_line  # noqa: PLC0415
    from envs.task import Evaluation  # noqa: PLC0415

    env = gym.make(task)
    try:
        expert = DeadlineExpert(env)
        for seed in seeds:
            env.reset(seed=seed)
            expert.reset()
            over = False
            while not over:
                _, _, term, trunc, info = env.step(expert.action())
                over = bool(term or trunc)
            ev = Evaluation.from_info(info)
            row = {"seed": seed, "correct": ev.correct, "lost": ev.lost, "success": ev.success}
            append_line(Path(log), json.dumps(row))
    finally:
        env.close()


def _teacher_rows(out: Path) -> dict[int, dict[str, Any]]:
    """The teacher's episodes already in the logs under ``out``, by seed."""
    from configs.files import complete_lines  # noqa: PLC0415

    return {
        r["seed"]: r
        for log in sorted(out.glob("teacher_*.jsonl"))
        for r in (json.loads(line) for line in complete_lines(log))
    }


def compare_teacher(task: str, failed: Sequence[int], *, workers: int, out: Path) -> dict[str, Any]:
    """The teacher (the scheduler's rule on ground truth) on the seeds the policy failed.

    Returns:
        ``teacher_episodes`` (the seeds replayed), ``teacher_failed_too`` (of those, the
        episodes the teacher fails as well) and ``teacher_lost`` (the tiles it loses on them).
    """
    have = _teacher_rows(out)
    missing = [s for s in failed if s not in have]
    in_workers(partial(_teacher, task), missing, workers, out, "teacher_{}.jsonl")
    rows = _teacher_rows(out)
    mine = [rows[s] for s in failed if s in rows]
    return {
        "teacher_episodes": len(mine),
        "teacher_failed_too": sum(not r["success"] for r in mine),
        "teacher_lost": sum(r["lost"] for r in mine),
    }


def stream_facts(task: str) -> tuple[int, float]:
    """(slots of the rung's design, its stream's supply rate [tiles/min]), from one env."""
    import gymnasium as gym  # noqa: PLC0415

    import envs  # noqa: F401, PLC0415 - registers the ladder

    env = gym.make(task)
    try:
        u = env.unwrapped
        return len(u.task.slot_class), 60.0 / float(u.cell.cfg.tiles.stream_period)  # type: ignore[attr-defined]
    finally:
        env.close()


def _same_soak(out: Path, task: str, policy: str) -> None:
    """Record the soak's task and policy in ``out``; refuse a folder of another soak.

    Raises:
        ConfigError: ``out`` holds the episodes of another task or policy.
    """
    from configs import ConfigError  # noqa: PLC0415

    path = out / SETTINGS
    mine = {"task": task, "policy": policy}
    if path.is_file():
        theirs = json.loads(path.read_text(encoding="utf-8"))
        if theirs != mine:
            raise ConfigError(
                f"{out} holds the soak of {theirs['policy']} on {theirs['task']}, not of "
                f"{policy} on {task}: give another --out"
            )
        return
    out.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(mine) + "\n", encoding="utf-8")


def soak(
    task: str,
    policy: str,
    tiles: int,
    *,
    first_seed: int,
    workers: int,
    out: Path,
    teacher: bool = False,
) -> dict[str, Any]:
    """Play until ``tiles`` tiles were supplied (resuming ``out``); the tally as a dict.

    With ``teacher``, the teacher also plays every seed the policy failed (`compare_teacher`).
    """
    _same_soak(out, task, policy)
    slots, supply = stream_facts(task)
    seeds = list(range(first_seed, first_seed + math.ceil(tiles / slots)))
    have = {e.seed for e in read_episodes(out)}
    t0 = time.monotonic()
    missing = [s for s in seeds if s not in have]
    in_workers(partial(_play, task, policy), missing, workers, out, "worker_{}")
    wanted = set(seeds)
    played = [e for e in read_episodes(out) if e.seed in wanted]
    result = asdict(tally(played, supply))
    if teacher:
        failed = sorted(e.seed for e in played if not e.success)
        result.update(compare_teacher(task, failed, workers=workers, out=out))
    result.update(
        task=task, policy=policy, seeds=[seeds[0], seeds[-1]], workers=workers,
        soak_wall_s=time.monotonic() - t0,
    )  # fmt: skip
    return result


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line (see the module docstring)."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", default=TASK)
    ap.add_argument("--policy", default=POLICY, help="an apps.evaluate policy name or path")
    ap.add_argument("--tiles", type=int, default=10_000, help="tiles supplied, at least")
    ap.add_argument("--first-seed", type=int, default=FIRST_SEED)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", type=Path, default=Path("out/stream_soak"))
    ap.add_argument(
        "--teacher",
        action="store_true",
        help="also play the teacher (the scheduler's rule on ground truth) on the failed seeds",
    )
    args = ap.parse_args(argv)
    if args.tiles < 1 or args.workers < 1:
        ap.error(f"--tiles {args.tiles}, --workers {args.workers}: each at least 1")
    result = soak(
        args.task,
        args.policy,
        args.tiles,
        first_seed=args.first_seed,
        workers=args.workers,
        out=args.out,
        teacher=args.teacher,
    )
    print(
        f"{result['episodes']} episodes, {result['tiles']} tiles: {result['correct']} correct "
        f"({100 * result['correct_share']:.2f} %, 95 % interval "
        f"{100 * result['correct_low']:.2f}-{100 * result['correct_high']:.2f} %), "
        f"{result['misplaced']} misplaced, {result['dropped']} dropped, {result['lost']} lost, "
        f"{result['stranded']} stranded, {result['left']} left; "
        f"{100 * result['episodes_complete']:.1f} % of episodes complete; "
        f"{result['tiles_per_min']:.1f} tiles/min (supply {result['supply_per_min']:.1f})"
    )
    if "teacher_episodes" in result:
        print(
            f"teacher on the {result['teacher_episodes']} failed seeds: fails "
            f"{result['teacher_failed_too']} of them too, losing {result['teacher_lost']} tiles"
        )
    return write_result(args.out / "soak.json", result, f" ({result['soak_wall_s']:.0f} s wall)")


__all__ = [
    "FIRST_SEED",
    "POLICY",
    "TASK",
    "SoakTally",
    "compare_teacher",
    "deal",
    "in_workers",
    "main",
    "soak",
    "tally",
    "wilson",
]

if __name__ == "__main__":
    run_cli(main)
