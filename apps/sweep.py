r"""Sweeps as Ray tasks: tasks x algorithms x training seeds, and the evaluation of policies.

Run::

    python -m apps.sweep --config baselines --out runs/sweep              # local Ray, 2 CPUs
    python -m apps.sweep --config baselines --out runs/sweep --address auto   # a cluster
    nice -n 19 python -m apps.sweep --config baselines --num-cpus 1 --niceness 19 \\
        --tasks MosaicStream-v0 MosaicOneTileJoint-v0   # some rows, one run at a time, niced

A sweep file (``configs/sweeps/*.yaml``, keys of `SweepConfig`) lists entries; a ``train``
entry trains one run per seed (a ``configs/train`` preset with the seed replaced) and then
evaluates the final model on its task's held-out protocol; a ``policy`` entry (any name of
`agents.policies`) is evaluated once. Each (entry, seed) is one Ray task with one CPU; without
``--address`` a local instance is started (``ray.init(num_cpus=..., include_dashboard=False)``),
with it the same command runs on a cluster (every node needs the project on ``PYTHONPATH``).
``--tasks`` keeps the entries of the given tasks only; ``--niceness`` sets every run's
scheduling niceness (default 0: Ray's workers start at 15 and starve on a busy host; on a host
shared with others, 19).

Results are written as they finish: ``<out>/<task>/<entry>/seed_<k>/result.json`` (and the
run's model, monitor CSVs and ``episodes.jsonl``) plus one line per finished run in
``<out>/results.jsonl``; a rerun skips the runs whose ``result.json`` exists. Every result file
is written whole or not at all (`configs.files`); a run killed while training has no completion
marker and is trained again, one killed while evaluating keeps its trained model and the
episodes already logged. A run whose Ray worker dies is retried (``--max-retries``, default
`RUN_RETRIES`); a run that still fails is logged with its error, the others finish, and the
command ends with one ``error:`` line naming the failed runs (exit status 1). At the end:
``<out>/summary.md`` and ``summary.json`` (per task and entry, labelled with what ran: the id and
the env keys a training preset or the entry changed, e.g. ``MosaicDecision6-v0 (max_slots=2)``;
the IQM over runs with its 95 %
stratified-bootstrap interval of every protocol metric, and the compute used) and
``<out>/curves.png`` (training success and return against steps, mean over seeds with a 95 %
bootstrap band).
"""

from __future__ import annotations

import json
import os
import re
import time
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from agents.errors import AgentError
from agents.protocol import METRICS
from apps.cli import CommandParser, run_cli
from apps.results.sweep_summary import summarize
from configs import ConfigError, from_dict, load_yaml
from configs.files import append_line, write_json
from envs.cell.rendering import RENDER_ENV_VAR, rendering_backend, use_headless_rendering

RESULT_FILE = "result.json"
"""Per-run result file."""
RESULTS_LOG = "results.jsonl"
"""One line per finished run, appended as runs finish."""
DEFAULT_CPUS = 2
"""CPUs of the local Ray instance when no ``--address`` is given."""
BC_SEED_STRIDE = 10_000
"""Demonstration reset seeds of a clone run start at its seed x this."""
WORKER_NICENESS = 0
"""Default scheduling niceness of a run (Ray's default for workers, 15, starves them on a busy
host); ``--niceness`` changes it."""
NICENESS_RANGE = (-20, 19)
"""Allowed niceness values (POSIX), inclusive."""
RUN_RETRIES = 2
"""Times Ray runs a run again whose worker process died (killed, out of memory) before it is
reported failed; an error raised by the run itself is not retried (it would fail again)."""


class SweepError(ConfigError):
    """A sweep file or entry that cannot run (unknown key, entry without train or policy)."""


class SweepRunsFailed(AgentError):
    """Some runs of a sweep failed (after their retries); the others finished and are reported."""


@dataclass(frozen=True)
class SweepEntry:
    """One line of the table.

    Attributes:
        name: Row label.
        task: Ladder id the entry is evaluated on (and trains on, unless its preset says).
        train: A ``configs/train`` preset name or path ("" for a policy entry).
        policy: A policy name of `agents.policies` ("" for a train entry).
        timesteps: Override of the preset's ``total_timesteps`` (0: keep).
        env: Extra env overrides of training and evaluation.
        bc_episodes: Behaviour cloning: record this many privileged-expert episodes on the
            task (reset seeds from seed x 10000, never the held-out ones) and clone them
            (`agents.learning.decision_bc`); 0: not a clone entry.
        bc_config: The clone's `agents.learning.decision_bc.BCConfig` (a name in ``configs/`` or a
            path):
            ``bc`` the flat MLP, ``bc_pair`` the pair scorer.
    """

    name: str
    task: str
    train: str = ""
    policy: str = ""
    timesteps: int = 0
    env: Mapping[str, Any] = field(default_factory=dict)
    bc_episodes: int = 0
    bc_config: str = "bc"

    def __post_init__(self) -> None:
        if bool(self.train) + bool(self.policy) + bool(self.bc_episodes) != 1:
            raise SweepError(
                f"sweep entry {self.name!r}: give exactly one of train, policy or bc_episodes"
            )

    @property
    def learned(self) -> bool:
        """The entry trains one run per seed."""
        return bool(self.train or self.bc_episodes)

    @property
    def slug(self) -> str:
        """File-system name of the entry."""
        return re.sub(r"[^A-Za-z0-9_.-]+", "_", self.name).strip("_")


@dataclass(frozen=True)
class SweepConfig:
    """A sweep.

    Attributes:
        entries: The entries.
        seeds: Training seeds of every train entry (>= 3 for a reported result).
        eval_seeds: Override of the tasks' held-out seeds, inclusive (lo, hi); empty: keep.
    """

    entries: tuple[SweepEntry, ...]
    seeds: tuple[int, ...] = (0, 1, 2)
    eval_seeds: tuple[int, ...] = ()


def load_sweep(name_or_path: str | Path) -> SweepConfig:
    """Load a sweep from ``configs/sweeps/`` (by stem) or a path, strictly.

    Raises:
        ConfigError: Unknown key or bad value.
    """
    data = load_yaml(name_or_path, "sweeps")
    entries = tuple(
        from_dict(SweepEntry, dict(e), source=str(name_or_path)) for e in data.pop("entries", [])
    )
    if not entries:
        raise SweepError(f"sweep {name_or_path}: no entries")
    data = {k: tuple(v) if isinstance(v, list) else v for k, v in data.items()}
    return from_dict(SweepConfig, {**data, "entries": entries}, source=str(name_or_path))


@dataclass(frozen=True)
class RunSpec:
    """One Ray task: an entry and a seed (seed -1 for a policy entry).

    Attributes:
        entry: The entry.
        seed: Training seed.
        folder: Output folder of the run.
        eval_seeds: Evaluation seeds override, inclusive (lo, hi), or ().
        niceness: Scheduling niceness the run sets for itself.
    """

    entry: SweepEntry
    seed: int
    folder: str
    eval_seeds: tuple[int, ...] = ()
    niceness: int = WORKER_NICENESS


def select_tasks(cfg: SweepConfig, tasks: Sequence[str]) -> SweepConfig:
    """The sweep restricted to the entries of ``tasks`` (all entries when empty).

    Raises:
        SweepError: A task with no entry in the sweep.
    """
    if not tasks:
        return cfg
    known = {e.task for e in cfg.entries}
    missing = sorted(set(tasks) - known)
    if missing:
        raise SweepError(f"no sweep entry for task(s) {missing}; the sweep has {sorted(known)}")
    return replace(cfg, entries=tuple(e for e in cfg.entries if e.task in set(tasks)))


def plan(cfg: SweepConfig, out: Path, niceness: int = WORKER_NICENESS) -> list[RunSpec]:
    """Every run of a sweep, in entry order.

    Raises:
        SweepError: A niceness outside `NICENESS_RANGE`.
    """
    lo, hi = NICENESS_RANGE
    if not lo <= niceness <= hi:
        raise SweepError(f"niceness must be in [{lo}, {hi}], got {niceness}")
    runs = []
    for e in cfg.entries:
        base = out / e.task / e.slug
        seeds = cfg.seeds if e.learned else (-1,)
        for s in seeds:
            folder = base / (f"seed_{s}" if s >= 0 else "eval")
            runs.append(RunSpec(e, s, str(folder.resolve()), cfg.eval_seeds, niceness))
    return runs


def execute(spec: RunSpec) -> dict[str, Any]:
    """Train (train entries) and evaluate one run; writes and returns its result dict."""
    use_headless_rendering()
    try:  # Ray starts workers at niceness 15; the run sets the niceness it was planned with
        os.setpriority(os.PRIO_PROCESS, 0, spec.niceness)
    except PermissionError:
        pass
    import torch  # noqa: PLC0415

    from agents.policies import make_policy  # noqa: PLC0415
    from apps.evaluate import Protocol, evaluate_policy_set, task_protocol  # noqa: PLC0415

    torch.set_num_threads(1)
    e, folder = spec.entry, Path(spec.folder)
    folder.mkdir(parents=True, exist_ok=True)
    base, proto = task_protocol(e.task)
    preset = dict(base)
    if spec.eval_seeds:
        lo, hi = spec.eval_seeds
        proto = Protocol(tuple(range(lo, hi + 1)), proto.designs, proto.max_steps, proto.horizon_s)
    t0 = time.perf_counter()
    if e.train:
        base, policy_name, train_info = _train_sb3(spec, folder, base)
    elif e.bc_episodes:
        base, policy_name, train_info = _train_bc(spec, folder, base)
    else:
        base, policy_name, train_info = {**base, **dict(e.env)}, e.policy, {}
    pol = make_policy(policy_name, base, calibrate=True)
    rows, per = evaluate_policy_set([pol], proto, log=folder / "episodes.jsonl")
    eps = per[pol.label]
    runs = {m: float(np.mean([_metric(ep, m) for ep in eps])) for m in METRICS}
    out = {
        "entry": e.name,
        "task": e.task,
        "ran": ran_label(e.task, preset, base),
        "seed": spec.seed,
        "folder": spec.folder,
        "metrics": runs,
        "row": asdict(rows[0]),
        "wall_s": time.perf_counter() - t0,
        "cpus": 1,
        **train_info,
    }
    write_json(folder / RESULT_FILE, out)
    return out


def ran_label(task: str, preset: Mapping[str, Any], ran: Mapping[str, Any]) -> str:
    """What a run played: the task id, with the env keys that differ from its preset.

    E.g. ``MosaicDecision6-v0 (max_slots=2)`` for a training preset that shrinks the design.
    """
    changed = {k: v for k, v in ran.items() if preset.get(k) != v}
    return f"{task} ({', '.join(f'{k}={v}' for k, v in changed.items())})" if changed else task


def _train_sb3(
    spec: RunSpec, folder: Path, base: dict[str, Any]
) -> tuple[dict[str, Any], str, dict[str, Any]]:
    """Train an SB3 entry (or take its finished training): (env kwargs, model path, figures)."""
    from apps.train import load_train_config, train  # noqa: PLC0415

    e = spec.entry
    overrides: dict[str, Any] = {"seed": spec.seed, "task": e.task, "progress_bar": False}
    if e.timesteps:
        overrides["total_timesteps"] = e.timesteps
    cfg = load_train_config(e.train, **overrides)
    if e.env:
        cfg = replace(cfg, env={**dict(cfg.env), **dict(e.env)})
    result = _trained(folder) or train(cfg, folder)
    info = {
        "timesteps": result.timesteps,
        "train_wall_s": result.wall_s,
        "train_cpu_s": result.cpu_s,
        "steps_per_s": result.steps_per_s,
        "episodes": result.episodes,
    }
    return {**base, **dict(cfg.env)}, str(result.model_path), info


def _train_bc(
    spec: RunSpec, folder: Path, base: dict[str, Any]
) -> tuple[dict[str, Any], str, dict[str, Any]]:
    """Record expert demos and clone them: (env kwargs, clone path, figures)."""
    from agents.learning.decision_bc import load_bc_config, train_bc  # noqa: PLC0415
    from apps.record_demos import load, record  # noqa: PLC0415

    e = spec.entry
    root, ds = folder / "demos", f"mosaic/{e.slug.lower()}-seed{spec.seed}-v0"
    rec = record(
        e.bc_episodes,
        seed=spec.seed * BC_SEED_STRIDE,
        root=root,
        dataset_id=ds,
        env_kwargs={**dict(e.env), "obs_mode": "state"},
        expert=True,
        task=e.task,
        overwrite=True,
    )
    summary = train_bc(load(ds, root), folder, spec.seed, load_bc_config(e.bc_config))
    info = {
        "timesteps": rec.steps,
        "train_wall_s": summary.get("wall_s", 0.0),
        "train_cpu_s": summary["cpu_s"],
        "gradient_steps": summary["gradient_steps"],
        "episodes": rec.episodes,
        "train_accuracy": summary["train_accuracy"],
    }
    return {**base, **dict(e.env)}, summary["model_path"], info


def _trained(folder: Path) -> Any:
    """The `TrainResult` of a run folder that finished training already (None otherwise).

    A run whose evaluation failed after training is evaluated again without retraining; a run
    killed while training has no completion marker (`apps.train.finished_run`) and is trained
    again from the start.
    """
    from apps.train import finished_run  # noqa: PLC0415

    return finished_run(folder)


def _metric(ep: Any, name: str) -> float:
    """A protocol metric of an episode result (`apps.evaluate_results.episode_metrics`)."""
    from apps.evaluate_results import episode_metrics  # noqa: PLC0415

    return float(getattr(episode_metrics(ep), name))


def run_sweep(
    cfg: SweepConfig,
    out: Path,
    address: str | None = None,
    num_cpus: int = DEFAULT_CPUS,
    *,
    progress: bool = True,
    niceness: int = WORKER_NICENESS,
    max_retries: int = RUN_RETRIES,
) -> list[dict[str, Any]]:
    """Run every missing run of a sweep as Ray tasks; return all results (old and new).

    A run whose worker dies is run again up to ``max_retries`` times; a run that still fails
    (or raises) is logged with its error in ``results.jsonl`` and left out of the summary, and
    the other runs go on.

    Raises:
        SweepRunsFailed: After the summary is written, if any run failed.
    """
    if max_retries < 0:
        raise SweepError(f"max_retries must be >= 0, got {max_retries}")
    out.mkdir(parents=True, exist_ok=True)
    runs = plan(cfg, out, niceness)
    results: list[dict[str, Any]] = []
    failed: list[dict[str, Any]] = []
    todo: list[RunSpec] = []
    for spec in runs:
        path = Path(spec.folder) / RESULT_FILE
        if path.is_file():
            results.append(json.loads(path.read_text(encoding="utf-8")))
        else:
            todo.append(spec)
    if todo:
        new, failed = _run_on_ray(todo, out, address, num_cpus, max_retries, progress)
        results += new
    summarize(results, out)
    if failed:
        names = "; ".join(
            f"{r['task']} / {r['entry']} seed {r['seed']}: {r['error']}" for r in failed
        )
        raise SweepRunsFailed(
            f"{len(failed)} of {len(runs)} runs failed (see {out / RESULTS_LOG}; a rerun "
            f"retries them): {names}"
        )
    return results


def _run_on_ray(  # noqa: PLR0913, PLR0917
    todo: list[RunSpec],
    out: Path,
    address: str | None,
    num_cpus: int,
    max_retries: int,
    progress: bool,
) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """Run ``todo`` as Ray tasks, logging each result as it comes: (results, failed runs)."""
    import ray  # noqa: PLC0415 - heavy import

    results: list[dict[str, Any]] = []
    failed: list[dict[str, Any]] = []
    env_vars = {"PYTHONPATH": os.environ.get("PYTHONPATH", str(Path.cwd()))}
    env_vars[RENDER_ENV_VAR] = rendering_backend()
    if address:
        ray.init(address=address, runtime_env={"env_vars": env_vars})
    else:
        ray.init(num_cpus=num_cpus, include_dashboard=False, runtime_env={"env_vars": env_vars})
    try:
        remote = ray.remote(num_cpus=1, max_retries=max_retries, retry_exceptions=False)(execute)
        pending = {remote.remote(s): s for s in todo}
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            for ref in ready:
                spec = pending.pop(ref)
                try:
                    res = ray.get(ref)
                except Exception as exc:  # noqa: BLE001 - one failed run must not stop others
                    res = {
                        "entry": spec.entry.name,
                        "task": spec.entry.task,
                        "seed": spec.seed,
                        "error": repr(exc),
                    }
                append_line(out / RESULTS_LOG, json.dumps(res))
                if "error" in res:
                    failed.append(res)
                else:
                    results.append(res)
                if progress:
                    print(
                        f"[sweep] done {res['task']} / {res['entry']} seed {res['seed']}: "
                        f"{res.get('metrics', res.get('error'))}",
                        flush=True,
                    )
    finally:
        ray.shutdown()
    return results, failed


def main(argv: list[str] | None = None) -> list[dict[str, Any]]:
    """Command line (see the module docstring)."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", required=True, help="name in configs/sweeps/ or a YAML path")
    ap.add_argument("--out", type=Path, default=Path("runs/sweep"))
    ap.add_argument("--address", default=None, help="Ray cluster address (default: local)")
    ap.add_argument("--num-cpus", type=int, default=DEFAULT_CPUS, help="local Ray CPUs")
    ap.add_argument("--summary-only", action="store_true", help="re-summarise finished runs")
    ap.add_argument("--tasks", nargs="*", default=[], help="only the entries of these tasks")
    ap.add_argument(
        "--niceness", type=int, default=WORKER_NICENESS, help="scheduling niceness of each run"
    )
    ap.add_argument(
        "--max-retries",
        type=int,
        default=RUN_RETRIES,
        help="reruns of a run whose worker process died",
    )
    args = ap.parse_args(argv)
    cfg = select_tasks(load_sweep(args.config), args.tasks)
    if args.summary_only:
        results = [
            json.loads((Path(s.folder) / RESULT_FILE).read_text(encoding="utf-8"))
            for s in plan(cfg, args.out)
            if (Path(s.folder) / RESULT_FILE).is_file()
        ]
        summarize(results, args.out)
    else:
        results = run_sweep(
            cfg,
            args.out,
            args.address,
            args.num_cpus,
            niceness=args.niceness,
            max_retries=args.max_retries,
        )
    print((args.out / "summary.md").read_text(encoding="utf-8"))
    return results


__all__ = [
    "RunSpec",
    "SweepConfig",
    "SweepEntry",
    "SweepError",
    "SweepRunsFailed",
    "execute",
    "load_sweep",
    "main",
    "plan",
    "run_sweep",
    "select_tasks",
    "summarize",  # re-exported: the sweep writes it at the end
]

if __name__ == "__main__":
    run_cli(main)
