r"""The equivariant pixel policy on unseen shapes: learning curves against demonstrations.

Run (the whole curve; times on a 2-core machine are in the docs' pixel-policy page)::

    python -m benchmarks.learned.equivariant --out runs/equivariant
    python -m benchmarks.learned.equivariant --out runs/equivariant --demos 1 10 --seeds 0 \
        --runs disassembly:ideal                          # a part of it
    python -m benchmarks.learned.equivariant --out runs/equivariant --ship   # + checkpoints/

For each demonstration source (``disassembly``: finished mosaics taken apart, no expert;
``expert``: the privileged expert) and camera level (``ideal``; ``realistic``: lens
distortion and exposure blur), the demonstrations are recorded once on the rung's training
designs (`agents.equivariant.collect`, ``max(demos)`` episodes, cached as ``data/*.npz``).
Every (count, seed) run trains on the first ``count`` episodes (`agents.equivariant.train`),
then plays the evaluation rungs' held-out protocol (seeds 1000-1019, the eval designs hexagon
and trencadis, whose shapes training never shows) through `apps.evaluate` with the env's
action masks. The qualitative theory plays the same pictures (`agents.experts.theory`, its
tile rows perceived from the input camera at the same image size) at each camera level.

CPU-minutes per run: training, plus the run's share of recording (CPU per episode recorded x
count); evaluation is listed apart. A run already trained (``summary.json``) or evaluated
(``eval.json``) is kept. Writes ``results.json`` (per run, and IQM with 95 % intervals over
seeds) and ``curves.png``.
"""

from __future__ import annotations

import json
import shutil
import time
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

from agents.equivariant.collect import collect
from agents.equivariant.config import (
    EQUIVARIANT_CONFIG,
    EquivariantConfig,
    load_equivariant_config,
)
from agents.equivariant.policy import save_policy
from agents.equivariant.records import SOURCES, StepRecords, load_records, save_records
from agents.equivariant.train import train
from agents.policies import make_policies, parse_pairs
from agents.protocol import iqm_ci
from apps.cli import CommandParser, run_cli
from apps.evaluate import Protocol, evaluate_policy_set, task_protocol
from configs import ConfigError, load_config
from configs.files import write_json
from envs.cell.rendering import use_headless_rendering

CURVES_CONFIG = "equivariant_curves"
"""Bundled config name (``configs/equivariant_curves.yaml``)."""
CHECKPOINTS = Path(__file__).resolve().parents[2] / "checkpoints"
"""Where ``--ship`` copies the shipped policies."""
NAME = "EquiMatch"
"""The policy's name in checkpoint folders and tables."""
THEORY = "agents.experts.theory:TheoryPolicy"
"""The qualitative theory on ``objects`` rows (perceived from the input camera)."""
TRANSPORTER_ANCHOR = {1: 0.638, 10: 0.906, 100: 0.986}
"""Equivariant Transporter on Ravens ``assembling-kits`` (unseen kits), success by
demonstrations (Huang et al., RSS 2022): the published anchor the targets are set against."""


@dataclass(frozen=True)
class CurvesConfig:
    """What the curves run.

    Attributes:
        task: Rung whose training designs the demonstrations come from.
        evaluate: Evaluations by name: env overrides of the rung played on its held-out
            protocol (``{}``: as registered; ``{rotation_frame: shape}``: rotation indices
            counted modulo each figure's symmetry, `envs.indexing`).
        image_size: Camera image (height, width) [px].
        data_seed: Seed of the first demonstration episode.
        demos: Demonstration counts (episodes).
        seeds: Training seeds per count.
        runs: The (demonstration source, camera level) curves, as ``source:camera``
            (sources: `agents.equivariant.records.SOURCES`; levels: ``camera_levels``).
        camera_levels: Cell overrides of each camera level.
        ship_demos: Counts whose seed-0 policy ``--ship`` copies to ``checkpoints/``.
        theory_image_sizes: Picture sizes (height, width) [px] the theory's tile rows are
            perceived from: the policy's own, and the camera's full resolution.
    """

    task: str = "MosaicHeldOutDesigns-v1"
    evaluate: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    image_size: tuple[int, int] = (96, 128)
    data_seed: int = 100000
    demos: tuple[int, ...] = (1, 10, 100, 1000)
    seeds: tuple[int, ...] = (0, 1, 2)
    runs: tuple[str, ...] = ("disassembly:ideal", "expert:ideal")
    camera_levels: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    ship_demos: tuple[int, ...] = (100, 10)
    theory_image_sizes: tuple[tuple[int, int], ...] = ((96, 128), (492, 656))


def records_for(
    out: Path, source: str, camera: str, *, episodes: int, cfg: EquivariantConfig, cc: CurvesConfig
) -> tuple[StepRecords, float]:
    """The recorded demonstrations of a (source, camera) and CPU seconds per episode recorded."""
    path = out / "data" / f"{source}_{camera}.npz"
    meta = path.with_suffix(".json")
    if path.is_file() and meta.is_file():
        rec = load_records(path, task=cc.task, cfg=cfg, image_size=cc.image_size)
        info = json.loads(meta.read_text(encoding="utf-8"))
        if rec.header.episodes >= episodes:
            return rec, float(info["cpu_s_per_episode"])
    cpu0 = time.process_time()
    rec = collect(
        cc.task,
        source,
        episodes,
        cfg,
        image_size=cc.image_size,
        camera=camera,
        cell=dict(cc.camera_levels.get(camera, {})) or None,
        seed=cc.data_seed,
    )
    per = (time.process_time() - cpu0) / episodes
    save_records(path, rec)
    write_json(meta, {"cpu_s_per_episode": per, "steps": len(rec.tile), "episodes": episodes})
    return rec, per


def base_env(name: str, camera: str, cc: CurvesConfig) -> tuple[dict[str, Any], Protocol]:
    """Env overrides and held-out protocol of an evaluation at a camera level."""
    base, proto = task_protocol(cc.task)
    base = {**base, **dict(cc.evaluate[name])}
    level = dict(cc.camera_levels.get(camera, {}))
    if level:
        base = {**base, "cell": level}
    return base, proto


def evaluate_model(model: Path, camera: str, cc: CurvesConfig) -> dict[str, dict[str, float]]:
    """Slots filled and success of a policy file on every evaluation rung."""
    out: dict[str, dict[str, float]] = {}
    for name in cc.evaluate:
        base, proto = base_env(name, camera, cc)
        cpu0 = time.process_time()
        rows, _ = evaluate_policy_set(make_policies([str(model)], base), proto)
        out[name] = {
            "filled": rows[0].filled,
            "success": rows[0].success_rate,
            "misplaced": rows[0].misplaced,
            "cpu_s": time.process_time() - cpu0,
        }
    return out


def evaluate_theory(
    camera: str, cc: CurvesConfig, size: tuple[int, int]
) -> dict[str, dict[str, float]]:
    """The qualitative theory on tile rows perceived from pictures of ``size`` (h, w) [px]."""
    out: dict[str, dict[str, float]] = {}
    for name in cc.evaluate:
        base, proto = base_env(name, camera, cc)
        env = {
            **base,
            "obs_mode": "objects",
            "objects_source": "perception",
            "objects_image_size": list(size),
            "invalid_actions": "fail",  # the theory has no masks: a refused pick costs time
        }
        rows, _ = evaluate_policy_set(make_policies([THEORY], env), proto)
        out[name] = {"filled": rows[0].filled, "success": rows[0].success_rate}
    return out


def run_one(
    out: Path,
    rec: StepRecords,
    *,
    per_episode_s: float,
    count: int,
    seed: int,
    camera: str,
    cfg: EquivariantConfig,
    cc: CurvesConfig,
) -> dict[str, Any]:
    """Train and evaluate one (source, camera, count, seed) run (kept if already done)."""
    folder = out / f"{rec.header.source}_{camera}" / f"d{count}" / f"seed_{seed}"
    model = folder / "model.pt"
    summary_path = folder / "summary.json"
    if summary_path.is_file() and model.is_file():
        summary = json.loads(summary_path.read_text(encoding="utf-8"))
    else:
        part = rec.first_episodes(count)
        net, curve = train(part, cfg, seed=seed)
        train_s = curve[-1]["cpu_s"]
        meta = {
            "image_size": list(cc.image_size),
            "task": cc.task,
            "camera": camera,
            "source": rec.header.source,
            "demos": count,
            "seed": seed,
        }
        save_policy(model, net, cfg, meta)
        summary = {
            **meta,
            "steps": len(part.tile),
            "gradient_steps": cfg.steps,
            "train_cpu_s": train_s,
            "record_cpu_s": per_episode_s * count,
            "cpu_minutes": (train_s + per_episode_s * count) / 60,
            "train_hit": curve[-1]["train_hit"],
            "config": asdict(cfg),
        }
        write_json(summary_path, summary)
    eval_path = folder / "eval.json"
    if eval_path.is_file():
        evals = json.loads(eval_path.read_text(encoding="utf-8"))
    else:
        evals = evaluate_model(model, camera, cc)
        write_json(eval_path, evals)
    return {
        "source": rec.header.source,
        "camera": camera,
        "demos": count,
        "seed": seed,
        "summary": summary,
        "eval": evals,
        "model": str(model),
    }


def aggregate(runs: Sequence[dict[str, Any]], cc: CurvesConfig) -> list[dict[str, Any]]:
    """IQM and 95 % interval over seeds per (source, camera, count)."""
    table = []
    keys = sorted({(r["source"], r["camera"], r["demos"]) for r in runs})
    for source, camera, count in keys:
        mine = [
            r for r in runs if (r["source"], r["camera"], r["demos"]) == (source, camera, count)
        ]
        row: dict[str, Any] = {
            "source": source,
            "camera": camera,
            "demos": count,
            "runs": len(mine),
        }
        for name in cc.evaluate:
            for metric in ("filled", "success"):
                est = iqm_ci([r["eval"][name][metric] for r in mine])
                row[f"{name}_{metric}"] = est.text()
                row[f"{name}_{metric}_iqm"] = est.iqm
        row["cpu_minutes_max"] = round(max(r["summary"]["cpu_minutes"] for r in mine), 2)
        table.append(row)
    return table


def plot(
    path: Path, table: Sequence[dict[str, Any]], theory: dict[str, Any], cc: CurvesConfig
) -> None:
    """Slots filled against demonstrations, one panel per evaluation rung."""
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    fig, axes = plt.subplots(
        1, len(cc.evaluate), figsize=(5.5 * len(cc.evaluate), 4), squeeze=False
    )
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, name in zip(axes[0], cc.evaluate, strict=True):
        for i, (source, camera) in enumerate(sorted({(r["source"], r["camera"]) for r in table})):
            rows = sorted(
                (r for r in table if (r["source"], r["camera"]) == (source, camera)),
                key=lambda r: r["demos"],
            )
            ax.plot(
                [r["demos"] for r in rows],
                [r[f"{name}_filled_iqm"] for r in rows],
                "o-",
                color=colours[i % len(colours)],
                label=f"{NAME}, {source}, {camera}",
            )
        for j, (camera, res) in enumerate(sorted(theory.items())):
            ax.axhline(
                res[name]["filled"],
                ls="--",
                color=colours[(j + 4) % len(colours)],
                label=f"theory, {camera}",
            )
        ax.plot(
            list(TRANSPORTER_ANCHOR),
            list(TRANSPORTER_ANCHOR.values()),
            "kx",
            ms=8,
            label="Equivariant Transporter, Ravens kits (success)",
        )
        ax.set(
            xscale="log",
            xlabel="demonstrations (episodes)",
            ylabel="slots filled (held-out)",
            ylim=(0, 1.02),
            title=f"{cc.task}, rotation_frame {name}",
        )
        ax.grid(alpha=0.3)
    axes[0][-1].legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def ship(runs: Sequence[dict[str, Any]], cc: CurvesConfig, source: str, camera: str) -> list[Path]:
    """Copy the seed-0 policies of ``ship_demos`` to ``checkpoints/<task>/<name>_rgb/seed_0/``."""
    done = []
    for count in cc.ship_demos:
        run = next(
            (
                r
                for r in runs
                if (r["source"], r["camera"], r["demos"], r["seed"]) == (source, camera, count, 0)
            ),
            None,
        )
        if run is None:
            continue
        name = NAME if count == max(cc.ship_demos) else f"{NAME}-{count}demos"
        folder = CHECKPOINTS / cc.task / f"{name}_rgb" / "seed_0"
        folder.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(run["model"], folder / "model.pt")
        write_json(folder / "summary.json", {**run["summary"], "eval": run["eval"]})
        done.append(folder / "model.pt")
    return done


def theory_rows(out: Path, cc: CurvesConfig) -> dict[str, Any]:
    """The theory's rows at the camera levels of the curves (kept if already measured)."""
    rows: dict[str, Any] = {}
    for camera in sorted({p.partition(":")[2] for p in cc.runs}):
        for h, w in cc.theory_image_sizes:
            path = out / f"theory_{camera}_{h}x{w}.json"
            if not path.is_file():
                write_json(path, evaluate_theory(camera, cc, (h, w)))
            rows[f"{camera}, {h}x{w}"] = json.loads(path.read_text(encoding="utf-8"))
    return rows


def run_all(
    out: Path, cfg: EquivariantConfig, cc: CurvesConfig, *, theory: bool = True
) -> dict[str, Any]:
    """Every run of the curves, the theory rows, the table and the plot."""
    runs: list[dict[str, Any]] = []
    for pair in cc.runs:
        source, _, camera = pair.partition(":")
        if source not in SOURCES or camera not in cc.camera_levels:
            raise ConfigError(
                f"run {pair!r}: expected source:camera with a source in {list(SOURCES)} and a "
                f"camera level in {sorted(cc.camera_levels)}"
            )
        rec, per = records_for(out, source, camera, episodes=max(cc.demos), cfg=cfg, cc=cc)
        for count in cc.demos:
            for seed in cc.seeds:
                runs.append(
                    run_one(
                        out,
                        rec,
                        per_episode_s=per,
                        count=count,
                        seed=seed,
                        camera=camera,
                        cfg=cfg,
                        cc=cc,
                    )
                )
                write_json(out / "results.json", {"runs": runs})
    rows = theory_rows(out, cc) if theory else {}
    table = aggregate(runs, cc)
    write_json(out / "results.json", {"runs": runs, "table": table, "theory": rows})
    plot(out / "curves.png", table, rows, cc)
    return {"runs": runs, "table": table, "theory": rows}


def decision_timing(
    model: Path, task_id: str = "MosaicDecision16-v1", decisions: int = 20
) -> dict[str, Any]:
    """CPU milliseconds per decision of a policy file on a 16-tile, 16-slot rung.

    Per decision: cutting the observation into crops, and scoring every (tile, slot, turn),
    once with the file's own fine turns and once with only the 4 quarter turns (the same
    weights: the turn count sets how the maps are turned, not the weights). One thread.
    """
    import gymnasium as gym  # noqa: PLC0415
    import torch  # noqa: PLC0415

    from agents.equivariant.network import build_network  # noqa: PLC0415
    from agents.equivariant.policy import EquivariantPolicy  # noqa: PLC0415

    torch.set_num_threads(1)
    pol = EquivariantPolicy.load(model)
    env = gym.make(task_id, obs_mode="rgb", image_size=list(pol.image_size))
    out: dict[str, Any] = {"task": task_id, "decisions": decisions}
    try:
        obs, _ = env.reset(seed=1000)
        spec = env.get_wrapper_attr("task_spec")
        n = len(pol.cut(obs, spec)[0])  # the tiles the policy sees
        out["tiles_seen"], out["slots"] = n, len(spec.slots)
        t0 = time.process_time()
        for _ in range(decisions):
            pol.cut(obs, spec)
        out["crops_ms"] = (time.process_time() - t0) / decisions * 1e3
        for turns in sorted({pol.cfg.turns, 4}):
            cfg = replace(pol.cfg, turns=turns)
            net = build_network(cfg)
            net.load_state_dict(pol.net.state_dict())
            p = EquivariantPolicy(net, cfg, pol.image_size)
            p.logits(obs, spec)  # warm up
            t0 = time.process_time()
            for _ in range(decisions):
                p.logits(obs, spec)
            out[f"decision_ms_{turns}_turns"] = (time.process_time() - t0) / decisions * 1e3
    finally:
        env.close()
    return out


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line (see the module docstring)."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("runs/equivariant"))
    ap.add_argument("--demos", type=int, nargs="+", help="counts (default: the config's)")
    ap.add_argument("--seeds", type=int, nargs="+")
    ap.add_argument(
        "--runs", nargs="+", metavar="SOURCE:CAMERA", help="curves (default: the config's)"
    )
    ap.add_argument("--no-theory", action="store_true", help="skip the theory rows")
    ap.add_argument("--theory-only", action="store_true", help="only the theory rows (no training)")
    ap.add_argument(
        "--timing", type=Path, metavar="MODEL", help="only time a policy file's decisions"
    )
    ap.add_argument(
        "--ship",
        nargs="?",
        const="disassembly:ideal",
        metavar="SOURCE:CAMERA",
        help="copy the seed-0 policies of ship_demos to checkpoints/",
    )
    ap.add_argument(
        "--curves", default=CURVES_CONFIG, help="curves config (name in configs/ or path)"
    )
    ap.add_argument("--config", default=EQUIVARIANT_CONFIG, help="policy config (name or path)")
    ap.add_argument(
        "--set", nargs="*", default=[], metavar="KEY=VALUE", help="policy config overrides"
    )
    args = ap.parse_args(argv)
    over: dict[str, Any] = {
        k: tuple(v)
        for k, v in (("demos", args.demos), ("seeds", args.seeds), ("runs", args.runs))
        if v
    }
    cc = load_config(CurvesConfig, args.curves, **over)
    use_headless_rendering()
    if args.theory_only:
        rows = theory_rows(args.out, cc)
        print(json.dumps(rows))
        return rows
    if args.timing is not None:
        timing = decision_timing(args.timing)
        print(json.dumps(timing))
        return timing
    import torch  # noqa: PLC0415

    torch.set_num_threads(1)  # CPU-minutes of one core; two runs side by side on two cores
    result = run_all(
        args.out,
        load_equivariant_config(args.config, **parse_pairs(args.set)),
        cc,
        theory=not args.no_theory,
    )
    for row in result["table"]:
        print(json.dumps({k: v for k, v in row.items() if not k.endswith("_iqm")}))
    for camera, res in result["theory"].items():
        print(json.dumps({"theory": camera, **res}))
    if args.ship:
        source, _, camera = args.ship.partition(":")
        for path in ship(result["runs"], cc, source, camera or "ideal"):
            print(f"shipped {path}")
    return result


__all__ = ["CURVES_CONFIG", "CurvesConfig", "aggregate", "evaluate_model", "main", "run_all"]

if __name__ == "__main__":
    run_cli(main)
