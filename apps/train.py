r"""Train any stable-baselines3 algorithm on `MosaicAssembly-v0` from a YAML in ``configs/train/``.

Run::

    python -m apps.train --config configs/train/pick_place_discrete.yaml \\
        [--timesteps N] [--out runs/NAME] [--seed S]

The run folder gets ``model.zip`` (final model), ``checkpoints/`` (`CheckpointCallback`),
``tb/`` (TensorBoard), ``monitor/`` (per-env episode CSVs with ``is_success``),
``train_config.yaml`` (the resolved configuration; `apps.evaluate` rebuilds the env from it),
``reward_terms.csv`` (per training episode: the step it ended at and the sum of each named reward
term of the env, `agents.learning.wrappers.EpisodeRewardTerms`) and ``summary.json`` (timesteps,
wall time, steps/s, first/last episode returns, last episodes' mean of each reward term).

The policy is picked from the observation space when ``policy: auto``: ``MultiInputPolicy``
for Dict observations, ``CnnPolicy`` for image Boxes, ``MlpPolicy`` otherwise.
"""

from __future__ import annotations

import dataclasses
import importlib
import json
import sys
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import yaml
from gymnasium import spaces

from agents.learning.algorithms import algorithm_class
from agents.learning.demos import DEFAULT_ROOT as DEMO_ROOT
from agents.learning.wrappers import (
    EPISODE_TERMS_KEY,
    EpisodeProgress,
    EpisodeRewardTerms,
    FlatDiscreteActions,
    ReachShaping,
    cpu_seconds,
)
from apps.cli import CommandParser, run_cli
from apps.results.monitor_log import monitor_episodes, succeeded
from apps.train_extras import (
    clone_before_learning,
    demo_callbacks,
    policy_kwargs_for,
    resolve_algo_kwargs,
)
from configs import ConfigError, from_dict, load_yaml
from configs.checks import check_fields, checked
from configs.files import atomic_path, write_json, write_text
from envs import ENV_ID
from envs.cell.config import REPO_ROOT
from envs.cell.rendering import use_headless_rendering

"""Gymnasium id of the environment (the ``envs:`` prefix imports and registers it)."""
VEC_ENVS = ("dummy", "subproc")
"""Allowed ``vec_env`` values."""
POLICIES = ("auto", "MlpPolicy", "CnnPolicy", "MultiInputPolicy")
"""Allowed ``policy`` values."""
RETURN_WINDOW = 100
"""Episodes averaged for the first/last returns of ``summary.json``."""
TERMS_FILE = "reward_terms.csv"
"""Per-episode reward-term sums of a run."""
LOG_WINDOW = 20
"""Recent episodes averaged in a progress line."""
SUMMARY_FILE = "summary.json"
"""The run's summary, written last: its presence marks a finished run (`finished_run`)."""
MONITORED = ("is_success", "filled", "cpu_s")
"""``info`` entries of an episode's last step written to the Monitor CSVs (success, fraction of
slots filled, CPU seconds of the training process then:
`agents.learning.wrappers.EpisodeProgress`)."""
MODEL_FILE = "model.zip"
"""The run's final model."""


class TrainError(ConfigError):
    """A training configuration that cannot run (unknown algorithm, policy or env key)."""


@dataclass(frozen=True)
class TrainConfig:
    """One training run.

    Attributes:
        algo: stable-baselines3 algorithm class name (``PPO``, ``A2C``, ``DQN``, ``SAC``,
            ``TD3``, ``DDPG``; ``sb3_contrib`` ones too when installed).
        policy: One of `POLICIES` (``auto`` picks from the observation space), or a policy
            class as ``module:Class`` (``agents.pair.maskable_policy:PairScorerPolicy``).
        total_timesteps: Env steps over all envs.
        n_envs: Parallel envs.
        vec_env: ``dummy`` (one process) or ``subproc`` (one process per env).
        seed: Seed of the algorithm and of the envs (env i gets seed + i).
        max_episode_steps: `TimeLimit` of the training envs [steps]; 0 keeps the registered one.
        env: Flat `EnvConfig` overrides (``envs/env_config.py``), e.g. ``action_mode``.
        algo_kwargs: Keyword arguments of the algorithm (``n_steps``, ``learning_rate``...).
        policy_kwargs: ``policy_kwargs`` of the algorithm (``net_arch``...).
        checkpoint_freq: Env steps (over all envs) between checkpoints; 0: none.
        tensorboard: Write TensorBoard logs to ``<out>/tb``.
        progress_bar: Show SB3's progress bar (tqdm + rich).
        torch_threads: ``torch.set_num_threads`` (shared CPUs: keep 1).
        device: Torch device (``cpu``, ``cuda``, ``auto``).
        verbose: SB3 verbosity (0, 1, 2).
        flatten_actions: Wrap the envs in `agents.learning.wrappers.FlatDiscreteActions`
            (MultiDiscrete
            -> one Discrete over all combinations).
        max_wall_s: Stop ``learn`` after this wall time [s] even before ``total_timesteps``;
            0: no limit (the final model is saved either way).
        max_cpu_s: The same limit in CPU time of the training process [s] (children included).
        demos: Minari dataset id of demonstrations (``out/minari``) for ``bc_epochs``.
        bc_epochs: Epochs of behaviour cloning of the actor on ``demos`` before learning
            (SAC; `agents.learning.rlpd.clone_actor`); 0: none. ``algo_kwargs`` keys ending in
            ``_class`` may name a class as ``module:attr`` (`apps.train_extras`), e.g.
            ``replay_buffer_class: agents.learning.rlpd:DemoMixReplayBuffer``.
        bc_std_fit: Where the cloned actor's standard deviation is fitted around: ``mean``
            (the Gaussian's mean) or ``clipped`` (the mean clipped to the demonstrated
            actions' range, so saturated actions such as the vacuum do not read as spread;
            `agents.learning.rlpd.clone_actor`).
        task: A rung of the task ladder (``MosaicDecision6-v0``, `envs.tasks`): the envs are
            made from its id (its preset and episode limit; env i trains on its training
            design i mod count) and ``env`` overrides on top; "" uses `MosaicAssembly-v0`.
        log_every_s: When output is not a terminal, print a progress line (steps, steps/s,
            recent return and success) to the log this often [s] instead of a progress bar.
        reach_shaping: Weight of `agents.learning.wrappers.ReachShaping` on the training envs [1/m]
            (reward per metre the tool approaches the nearest tile; state observations);
            0: off. Evaluation always uses the env's own reward.
        normalize_obs: Standardise the observations with fixed statistics of ``demos``
            (`agents.learning.obs_norm.NormalizedStateExtractor`, saved with the model).
        residual_scale: Residual RL over the scripted low-level controller
            (`agents.learning.residual.ResidualExpertActions`): the agent's action, times this
            [action units], is added to the controller's; 0: off. Played the same way.
        hold_actor_steps: Keep the actor as it starts ``learn`` (e.g. cloned) for this many
            env steps while the critics learn (`agents.learning.rlpd.hold_actor`); 0: off.
        actor_bc_weight: Weight of a behaviour-cloning term in SAC's actor loss on the
            demonstration half of each batch (`agents.learning.actor_bc`: squared distance of the
            actor's deterministic action to the demonstrated one [action units^2], times the
            critic's mean magnitude; TD3+BC's alpha 2.5 is 0.4); 0: off. Needs
            ``replay_buffer_class: agents.learning.rlpd:DemoMixReplayBuffer``.
        actor_bc_decay_steps: Env steps over which ``actor_bc_weight`` falls linearly to 0;
            0: constant.
        init_clone: A pair-scorer clone ``.pt`` the ``PairScorerPolicy`` starts from
            (`agents.pair.from_clone`): its scorer shape, rows and belt timing fill
            ``policy_kwargs.features_extractor_kwargs`` and its weights are loaded into the
            actor (and an unshared critic's scorer), so the first actions are the clone's; a
            relative path is taken from the repository root; "": none.
        critic_warmup_steps: Env steps whose updates fit the critic only, the actor frozen
            (`agents.learning.critic_warmup`; PPO / MaskablePPO); 0: off.
        critic_warmup_lr: Learning rate of those updates; 0: the algorithm's.
    """

    algo: str = "PPO"
    policy: str = "auto"
    total_timesteps: int = checked(100_000, ge=1)
    n_envs: int = checked(1, ge=1)
    vec_env: str = checked("dummy", choices=VEC_ENVS)
    seed: int = 0
    max_episode_steps: int = checked(0, ge=0)
    env: Mapping[str, Any] = field(default_factory=dict)
    algo_kwargs: Mapping[str, Any] = field(default_factory=dict)
    policy_kwargs: Mapping[str, Any] = field(default_factory=dict)
    checkpoint_freq: int = checked(10_000, ge=0)
    tensorboard: bool = True
    progress_bar: bool = True
    torch_threads: int = checked(1, ge=1)
    device: str = "cpu"
    verbose: int = 0
    flatten_actions: bool = False
    max_wall_s: float = checked(0.0, ge=0)
    max_cpu_s: float = checked(0.0, ge=0)
    task: str = ""
    log_every_s: float = 30.0
    reach_shaping: float = checked(0.0, ge=0)  # [1/m]
    demos: str = ""
    bc_epochs: int = 0
    bc_std_fit: str = "mean"
    normalize_obs: bool = False
    residual_scale: float = checked(0.0, ge=0)
    hold_actor_steps: int = checked(0, ge=0)
    actor_bc_weight: float = checked(0.0, ge=0)
    actor_bc_decay_steps: int = checked(0, ge=0)
    init_clone: str = ""
    critic_warmup_steps: int = checked(0, ge=0)
    critic_warmup_lr: float = checked(0.0, ge=0)

    def __post_init__(self) -> None:
        check_fields(self, TrainError)
        if self.policy not in POLICIES and ":" not in self.policy:
            raise TrainError(
                f"unknown policy {self.policy!r}; allowed: {list(POLICIES)} or module:Class"
            )
        if (self.bc_epochs or self.normalize_obs) and not self.demos:
            raise TrainError("bc_epochs and normalize_obs need demos (a dataset id)")
        if self.bc_std_fit != "mean":
            from agents.learning.rlpd import STD_FITS  # noqa: PLC0415 - torch, only when set

            if self.bc_std_fit not in STD_FITS:
                raise TrainError(
                    f"bc_std_fit must be one of {list(STD_FITS)}, got {self.bc_std_fit!r}"
                )
        from envs.env_config import load_env_config  # noqa: PLC0415 - validates env keys

        load_env_config(**dict(self.env))
        if self.task:
            from envs.tasks import get_task  # noqa: PLC0415

            get_task(self.task)

    def to_dict(self) -> dict[str, Any]:
        """Plain dict (YAML-serialisable) of every field."""
        out = dataclasses.asdict(self)
        for key in ("env", "algo_kwargs", "policy_kwargs"):
            out[key] = _plain(dict(getattr(self, key)))
        return out


def _plain(value: Any) -> Any:
    """Tuples -> lists, recursively, so YAML stays plain."""
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value


def load_train_config(path: str | Path, **overrides: Any) -> TrainConfig:
    """Load a `TrainConfig` from a YAML path or a name in ``configs/train/``, strictly.

    Raises:
        ConfigError: Unknown key, wrong type, unknown env key, vec_env or policy.
    """
    data = load_yaml(path, "train")
    data.update({k: v for k, v in overrides.items() if v is not None})
    return from_dict(TrainConfig, data, source=str(path))


def pick_policy(policy: str, observation_space: spaces.Space) -> Any:
    """Resolve ``auto`` from the observation space (Dict -> MultiInputPolicy), import a class.

    Raises:
        TrainError: A ``module:Class`` that cannot be imported.
    """
    if ":" in policy:
        module, _, name = policy.partition(":")
        try:
            return getattr(importlib.import_module(module), name)
        except (ImportError, AttributeError) as exc:
            raise TrainError(f"cannot import policy {policy!r}: {exc}") from exc
    if policy != "auto":
        return policy
    if isinstance(observation_space, spaces.Dict):
        return "MultiInputPolicy"
    shape = getattr(observation_space, "shape", None) or ()
    if isinstance(observation_space, spaces.Box) and len(shape) == 3:
        return "CnnPolicy"
    return "MlpPolicy"


def make_env_fn(cfg: TrainConfig, index: int = 0) -> Any:
    """A zero-argument factory of training env ``index`` (``gym.make`` with the overrides).

    With a ``task``: the task's id, its training design ``index`` mod count, then ``env``.
    """
    kwargs: dict[str, Any] = dict(cfg.env)
    env_id = ENV_ID
    if cfg.task:
        from envs.tasks import get_task  # noqa: PLC0415

        task = get_task(cfg.task)
        env_id = f"envs:{task.id}"
        kwargs = {**task.design_kwargs("train", index), **kwargs}
    if cfg.max_episode_steps:
        kwargs["max_episode_steps"] = cfg.max_episode_steps

    def make() -> gym.Env:
        env = gym.make(env_id, **kwargs)
        if cfg.reach_shaping:
            env = ReachShaping(env, cfg.reach_shaping)
        if cfg.residual_scale:
            from agents.learning.residual import ResidualExpertActions  # noqa: PLC0415

            env = ResidualExpertActions(env, cfg.residual_scale)
        return FlatDiscreteActions(env) if cfg.flatten_actions else env

    return make


def make_vec(cfg: TrainConfig, monitor_dir: Path | None) -> Any:
    """The vectorised training envs (each wrapped in `Monitor` logging ``is_success``)."""
    from stable_baselines3.common.monitor import Monitor  # noqa: PLC0415
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv  # noqa: PLC0415

    if monitor_dir is not None:
        monitor_dir.mkdir(parents=True, exist_ok=True)

    def factory(i: int) -> Any:
        make = make_env_fn(cfg, i)

        def build() -> gym.Env:
            env = make()
            env.action_space.seed(cfg.seed + i)
            path = str(monitor_dir / str(i)) if monitor_dir is not None else None
            return Monitor(EpisodeRewardTerms(EpisodeProgress(env)), path, info_keywords=MONITORED)

        return build

    fns = [factory(i) for i in range(cfg.n_envs)]
    venv = (
        SubprocVecEnv(fns, start_method="spawn") if cfg.vec_env == "subproc" else DummyVecEnv(fns)
    )
    venv.seed(cfg.seed)
    return venv


@dataclass(frozen=True)
class TrainResult:
    """What a run produced.

    Attributes:
        out: Run folder.
        model_path: Final model (``model.zip``).
        timesteps: Env steps trained.
        wall_s: Wall time of ``learn`` [s].
        steps_per_s: timesteps / wall_s.
        episodes: Finished training episodes.
        first_return: Mean return of the first `RETURN_WINDOW` episodes (NaN if none).
        last_return: Mean return of the last `RETURN_WINDOW` episodes.
        first_success: Success rate of the first episodes.
        last_success: Success rate of the last episodes.
        last_terms: Mean per-episode sum of each named reward term over the last
            `RETURN_WINDOW` episodes ({} if the env names none).
        cpu_s: CPU time of ``learn`` [s] (this process and its children).
    """

    out: Path
    model_path: Path
    timesteps: int
    wall_s: float
    steps_per_s: float
    episodes: int
    first_return: float
    last_return: float
    first_success: float
    last_success: float
    last_terms: dict[str, float] = field(default_factory=dict)
    cpu_s: float = 0.0
    gradient_steps: int = 0
    """Gradient steps of behaviour cloning and ``learn`` (``_n_updates``; 0 if not kept)."""


def build_model(cfg: TrainConfig, venv: Any, tensorboard_log: str | None = None) -> Any:
    """The config's SB3 model on ``venv``, untrained (algorithm, policy, settings, seed)."""
    kwargs: dict[str, Any] = resolve_algo_kwargs(dict(cfg.algo_kwargs))
    if cfg.policy_kwargs or cfg.normalize_obs:
        kwargs["policy_kwargs"] = policy_kwargs_for(cfg, venv, DEMO_ROOT)
    if cfg.init_clone:
        from agents.pair.from_clone import clone_policy_kwargs, read_clone  # noqa: PLC0415

        clone = read_clone(clone_path(cfg.init_clone))
        kwargs["policy_kwargs"] = clone_policy_kwargs(clone, kwargs.get("policy_kwargs") or {})
    model = algorithm_class(cfg.algo)(
        pick_policy(cfg.policy, venv.observation_space),
        venv,
        seed=cfg.seed,
        device=cfg.device,
        verbose=cfg.verbose,
        tensorboard_log=tensorboard_log,
        **kwargs,
    )
    if cfg.init_clone:
        from agents.pair.from_clone import load_clone  # noqa: PLC0415

        load_clone(model.policy, clone)
    return model


def clone_path(path: str) -> Path:
    """``init_clone`` as a path: a relative one from the repository root."""
    p = Path(path)
    return p if p.is_absolute() else REPO_ROOT / p


def finished_run(out: Path) -> TrainResult | None:
    """The result of the run folder ``out`` if its training finished, else None.

    A run is finished once its `SUMMARY_FILE` exists: it is written (whole, by rename) after
    the final model, and removed when a run starts in the folder, so a run killed part-way is
    never taken as finished.
    """
    summary, model = out / SUMMARY_FILE, out / MODEL_FILE
    if not summary.is_file() or not model.is_file():
        return None
    data = json.loads(summary.read_text(encoding="utf-8"))
    data["out"], data["model_path"] = Path(data["out"]), Path(data["model_path"])
    return TrainResult(**data)


def _episode_stats(monitor_dir: Path) -> tuple[int, float, float, float, float]:
    """(episodes, first/last mean return, first/last success rate) from Monitor CSVs."""
    rows = sorted(  # (end time, return, success)
        (float(ep["t"]), float(ep["r"]), succeeded(ep)) for ep in monitor_episodes(monitor_dir)
    )
    if not rows:
        nan = float("nan")
        return 0, nan, nan, nan, nan
    arr = np.array(rows)
    first, last = arr[:RETURN_WINDOW], arr[-RETURN_WINDOW:]
    return (
        len(arr),
        float(first[:, 1].mean()),
        float(last[:, 1].mean()),
        float(first[:, 2].mean()),
        float(last[:, 2].mean()),
    )


def _wall_clock_stop(limit_s: float, clock: Any = time.perf_counter) -> Any:
    """A callback that ends ``learn`` once ``limit_s`` seconds of ``clock`` have passed."""
    from stable_baselines3.common.callbacks import BaseCallback  # noqa: PLC0415

    class WallClockStop(BaseCallback):
        def _on_training_start(self) -> None:
            self.t0 = clock()

        def _on_step(self) -> bool:
            return clock() - self.t0 < limit_s

    return WallClockStop()


class TermsLog:
    """Writes each finished training episode's reward-term sums to a CSV file.

    Columns: ``step`` (env steps over all envs when the episode ended) and one per term, in the
    order of the first episode (terms are fixed per env). Call `add` with a step's infos.

    Args:
        path: The CSV file (created, truncated).
    """

    def __init__(self, path: Path) -> None:
        self.path = path
        self.terms: list[str] = []
        self.rows: list[list[float]] = []
        path.write_text("", encoding="utf-8")

    def add(self, step: int, infos: Any) -> None:
        """Record the episodes that ended at ``step`` (infos of one vector step)."""
        for info in infos:
            sums = info.get(EPISODE_TERMS_KEY) if isinstance(info, dict) else None
            if not sums:
                continue
            with self.path.open("a", encoding="utf-8") as fh:
                if not self.terms:
                    self.terms = list(sums)
                    fh.write(",".join(["step", *self.terms]) + "\n")
                row = [float(step), *(float(sums.get(t, 0.0)) for t in self.terms)]
                fh.write(",".join(f"{v:.6g}" for v in row) + "\n")
            self.rows.append(row[1:])

    def recent(self, count: int) -> dict[str, float]:
        """Mean of each term over the last ``count`` episodes ({} before the first)."""
        if not self.rows:
            return {}
        mean = np.mean(self.rows[-count:], axis=0)
        return {t: float(v) for t, v in zip(self.terms, mean, strict=True)}


def _log_terms(log: TermsLog) -> Any:
    """A callback feeding each step's infos to ``log``."""
    from stable_baselines3.common.callbacks import BaseCallback  # noqa: PLC0415

    class LogTerms(BaseCallback):
        def _on_step(self) -> bool:
            log.add(int(self.model.num_timesteps), self.locals.get("infos", ()))
            return True

    return LogTerms()


def _log_progress(every_s: float, total: int, terms: TermsLog) -> Any:
    """A callback printing one progress line every ``every_s`` wall seconds (log files).

    The line ends with the recent mean of each non-zero reward term of ``terms``.
    """
    from stable_baselines3.common.callbacks import BaseCallback  # noqa: PLC0415

    class LogProgress(BaseCallback):
        def _on_training_start(self) -> None:
            self.t0 = self.last = time.perf_counter()

        def _on_step(self) -> bool:
            now = time.perf_counter()
            if now - self.last >= every_s:
                self.last = now
                buf = list(self.model.ep_info_buffer or [])
                ret = np.mean([e["r"] for e in buf]) if buf else float("nan")
                ok = np.mean([float(e.get("is_success", 0)) for e in buf]) if buf else float("nan")
                n = self.model.num_timesteps
                recent = terms.recent(LOG_WINDOW)
                parts = " ".join(f"{k} {v:.3f}" for k, v in recent.items() if v)
                print(
                    f"[train] {n}/{total} steps, {n / (now - self.t0):.0f} steps/s, "
                    f"return {ret:.2f}, success {ok:.2f} (last {len(buf)} episodes)"
                    + (f"; terms/episode (last {LOG_WINDOW}): {parts}" if parts else ""),
                    flush=True,
                )
            return True

    return LogProgress()


def _atomic_checkpoints(**kwargs: Any) -> Any:
    """SB3's `CheckpointCallback` whose model files are written whole or not at all."""
    from stable_baselines3.common.callbacks import CheckpointCallback  # noqa: PLC0415

    class AtomicCheckpoint(CheckpointCallback):
        def _on_step(self) -> bool:
            if self.n_calls % self.save_freq == 0:
                with atomic_path(self._checkpoint_path(extension="zip")) as tmp:
                    self.model.save(str(tmp))
            return True

    return AtomicCheckpoint(**kwargs)


def train(cfg: TrainConfig, out: Path) -> TrainResult:
    """Train ``cfg`` and write the run folder ``out`` (see the module docstring).

    Every result file is written whole or not at all; ``summary.json`` last (`finished_run`).
    """
    import torch  # noqa: PLC0415 - heavy import

    torch.set_num_threads(cfg.torch_threads)
    out.mkdir(parents=True, exist_ok=True)
    (out / SUMMARY_FILE).unlink(missing_ok=True)  # unfinished until the summary is back
    write_text(out / "train_config.yaml", yaml.safe_dump(cfg.to_dict(), sort_keys=False))
    monitor_dir = out / "monitor"
    venv = make_vec(cfg, monitor_dir)
    try:
        model = build_model(cfg, venv, tensorboard_log=str(out / "tb") if cfg.tensorboard else None)
        terms = TermsLog(out / TERMS_FILE)
        callbacks = [_log_terms(terms), *demo_callbacks(cfg)]
        if cfg.critic_warmup_steps:
            from agents.learning.critic_warmup import critic_warmup  # noqa: PLC0415

            callbacks.append(critic_warmup(cfg.critic_warmup_steps, cfg.critic_warmup_lr))
        show_bar = cfg.progress_bar and sys.stdout.isatty()
        if not show_bar and cfg.log_every_s > 0:
            callbacks.append(_log_progress(cfg.log_every_s, cfg.total_timesteps, terms))
        if cfg.max_wall_s:
            callbacks.append(_wall_clock_stop(cfg.max_wall_s))
        if cfg.max_cpu_s:
            callbacks.append(_wall_clock_stop(cfg.max_cpu_s, cpu_seconds))
        if cfg.checkpoint_freq:
            callbacks.append(
                _atomic_checkpoints(
                    save_freq=max(cfg.checkpoint_freq // cfg.n_envs, 1),
                    save_path=str(out / "checkpoints"),
                    name_prefix="model",
                )
            )
        t0, c0 = time.perf_counter(), cpu_seconds()
        bc_steps = 0
        if cfg.bc_epochs:
            bc_steps = clone_before_learning(
                model, cfg.demos, DEMO_ROOT, cfg.bc_epochs, cfg.seed, std_fit=cfg.bc_std_fit
            )
        model.learn(
            total_timesteps=cfg.total_timesteps,
            callback=callbacks,
            progress_bar=show_bar,
            tb_log_name=cfg.algo,
        )
        wall, cpu = time.perf_counter() - t0, cpu_seconds() - c0
        model_path = out / MODEL_FILE
        with atomic_path(model_path) as tmp:
            model.save(str(tmp))
        steps = int(model.num_timesteps)
    finally:
        venv.close()
    episodes, r0, r1, s0, s1 = _episode_stats(monitor_dir)
    result = TrainResult(
        out,
        model_path,
        steps,
        wall,
        steps / wall,
        episodes,
        r0,
        r1,
        s0,
        s1,
        terms.recent(RETURN_WINDOW),
        cpu,
        bc_steps + int(getattr(model, "_n_updates", 0)),
    )
    summary = {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(result).items()}
    write_json(out / SUMMARY_FILE, summary)
    return result


def main(argv: list[str] | None = None) -> TrainResult:
    """Command line: ``--config`` (required), ``--timesteps N``, ``--out DIR`` (``--help``)."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", required=True, help="YAML path or name in configs/train/")
    ap.add_argument("--timesteps", type=int, default=None, help="override total_timesteps")
    ap.add_argument("--seed", type=int, default=None, help="override seed")
    ap.add_argument("--n-envs", type=int, default=None, help="override n_envs")
    ap.add_argument("--max-cpu-s", type=float, default=None, help="override max_cpu_s [s]")
    ap.add_argument("--out", type=Path, default=None, help="run folder (default runs/<config>)")
    ap.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = ap.parse_args(argv)
    use_headless_rendering()
    overrides: dict[str, Any] = {
        "total_timesteps": args.timesteps,
        "seed": args.seed,
        "n_envs": args.n_envs,
        "max_cpu_s": args.max_cpu_s,
    }
    if args.no_progress:
        overrides["progress_bar"] = False
    cfg = load_train_config(args.config, **overrides)
    out = args.out or Path("runs") / Path(args.config).stem
    result = train(cfg, out)
    print(
        f"{cfg.algo} {result.timesteps} steps in {result.wall_s:.0f} s "
        f"({result.steps_per_s:.0f} steps/s), {result.episodes} episodes; return "
        f"{result.first_return:.2f} -> {result.last_return:.2f}, success "
        f"{result.first_success:.2f} -> {result.last_success:.2f}; model {result.model_path}"
    )
    return result


if __name__ == "__main__":
    run_cli(main)
