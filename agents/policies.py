"""Policies for evaluation, by name: scripted, random, open-loop, SB3 checkpoints, user objects.

`make_policy(spec, base_env)` resolves one name; every policy is a `Policy`: the env overrides
its spaces need, an optional wrapper, and a factory that binds it to a built env and returns a
``predict(obs, episode_start) -> action`` function. Names:

- ``scripted``: the scripted cell from camera images (`agents.scripted.agent.ScriptedAgent`),
  ``pick_place`` actions at ``scripted_image_size``.
- ``random``: uniform samples of the env's action space (seeded per episode); where the env
  offers action masks (``action_masks()``, the discrete modes) only among the allowed actions
  (``action_space.sample(mask=...)``), so it plays the ``-v1`` ids, which refuse the others.
- ``openloop``: the best open-loop sequence: the privileged expert's actions recorded on one
  training seed, replayed on every episode without looking (shows whether the encoding leaks).
- ``identity``: the open-loop sequence ``(i, i, 0)`` (decision level).
- a ``.pt`` path: a camera policy of `agents.camera.crop_scorer` or the equivariant pixel
  policy of `agents.equivariant.policy` (its file's ``kind`` says so; played on ``rgb``
  observations at its image size, the latter with the env's action masks) or a behaviour clone of
  `agents.learning.decision_bc`. A camera policy plays the env's action mode
  (`CAMERA_ACTION_MODES`): in
  ``pick_place_discrete`` its (tile, slot, turn), in ``pick_place`` that choice placed at the
  pose its figure fit measures (`agents.camera.continuous`; ``--env action_mode=pick_place``
  or ``camera.pt@action_mode=pick_place``).
- a path to an SB3 ``.zip``: loaded with the algorithm of its run's ``train_config.yaml``;
  its observation and action spaces must equal the env's, checked when it is bound. A run
  with ``residual_scale`` plays through `agents.learning.residual.ResidualExpertActions` (residual
  RL: the scripted controller's action plus the model's).
- ``module:attr``: a user's object. If ``attr`` has ``predict``, ``predict(obs)`` is called
  (SB3 style: a ``(action, state)`` tuple or an action); a class is instantiated with the env
  first; a plain function is called as ``f(obs) -> action``. An object with
  ``observation_space``/``action_space`` attributes has them checked against the env.

``NAME@KEY=VALUE[,KEY=VALUE]`` gives one policy its own env overrides.
"""

from __future__ import annotations

import importlib
import inspect
import zipfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import yaml
from gymnasium import spaces

from agents.learning.wrappers import FlatDiscreteActions
from configs import ConfigError

SCRIPTED_IMAGE_SIZE = (492, 656)
"""Default camera image size of the scripted agent (the camera's full resolution) [px]."""
SPACE_KEYS = ("action_mode", "obs_mode", "image_size", "depth", "rotation_bins")
"""Env keys that define a policy's action and observation spaces (taken from a model's run)."""
OPENLOOP_TRAIN_SEED = 0
"""Training seed on which ``openloop`` records the expert's sequence."""
ALGORITHMS = ("PPO", "A2C", "DQN", "SAC", "TD3", "DDPG")
"""Algorithms tried in turn for a checkpoint without a run config."""
CAMERA_ACTION_MODES = ("pick_place_discrete", "pick_place")
"""Action modes a camera policy plays: its scorer's choice, or that choice at fitted poses."""

Predict = Callable[[dict[str, Any], bool], np.ndarray]
"""A policy step: (observation, episode start) -> action."""


class PolicyError(ConfigError):
    """A policy name that cannot be resolved, or a policy whose spaces do not fit its env."""


@dataclass(frozen=True)
class Policy:
    """A policy to bind to an env.

    Attributes:
        label: Table label.
        env_kwargs: Env overrides of its env.
        factory: Binds it to a built env, returning a `Predict` (may raise `PolicyError`).
        wrap: Wrapper applied to its env (a trained model's `FlatDiscreteActions`), or None.
    """

    label: str
    env_kwargs: dict[str, Any]
    factory: Callable[[gym.Env], Predict]
    wrap: Callable[[gym.Env], gym.Env] | None = None


def sb3_observation_space(space: Any) -> Any:
    """The observation space as an SB3 model stores it (channel-last images transposed)."""
    from gymnasium import spaces  # noqa: PLC0415
    from stable_baselines3.common.preprocessing import (  # noqa: PLC0415
        is_image_space,
        is_image_space_channels_first,
    )
    from stable_baselines3.common.vec_env import VecTransposeImage  # noqa: PLC0415

    if isinstance(space, spaces.Dict):
        return spaces.Dict({k: sb3_observation_space(v) for k, v in space.spaces.items()})
    if is_image_space(space) and not is_image_space_channels_first(space):
        return VecTransposeImage.transpose_space(space)
    return space


def check_spaces(
    label: str, env: gym.Env, obs_space: Any, act_space: Any, *, sb3_view: bool = False
) -> None:
    """Raise `PolicyError` unless a policy's spaces equal the env's (None: not checked).

    ``sb3_view``: compare with the env's observation space as SB3 stores it.
    """
    env_obs = sb3_observation_space(env.observation_space) if sb3_view else env.observation_space
    for what, mine, theirs in (
        ("observation", obs_space, env_obs),
        ("action", act_space, env.action_space),
    ):
        if mine is not None and mine != theirs:
            raise PolicyError(
                f"policy {label!r}: its {what} space {mine} does not match the env's {theirs}; "
                "evaluate it on the task and env keys it was trained with"
            )


def _scripted(base: dict[str, Any], image_size: tuple[int, int], calibrate: bool) -> Policy:
    env_kwargs = {
        **base,
        "action_mode": "pick_place",
        "obs_mode": "rgb",
        "image_size": list(image_size),
    }

    def factory(env: gym.Env) -> Predict:
        from agents.scripted.agent import ScriptedAgent  # noqa: PLC0415 - vision stack

        agent = ScriptedAgent.from_env(env, calibrate=calibrate)

        def predict(obs: dict[str, Any], start: bool) -> np.ndarray:
            return agent.predict(obs, episode_start=np.array([start]))[0]

        return predict

    return Policy("scripted", env_kwargs, factory)


def _random(base: dict[str, Any]) -> Policy:
    def factory(env: gym.Env) -> Predict:
        space = env.action_space
        masked = isinstance(space, spaces.Discrete | spaces.MultiDiscrete) and _has_masks(env)

        def predict(obs: dict[str, Any], start: bool) -> np.ndarray:
            del obs, start
            if not masked:
                return np.asarray(space.sample())
            mask = np.asarray(env.get_wrapper_attr("action_masks")(), np.int8)
            if isinstance(space, spaces.MultiDiscrete):
                cuts = np.cumsum(space.nvec.ravel())[:-1]
                return np.asarray(space.sample(mask=tuple(np.split(mask, cuts))))
            return np.asarray(space.sample(mask=mask))

        return predict

    return Policy("random", dict(base), factory)


def _has_masks(env: gym.Env) -> bool:
    """The env (or a wrapper) has ``action_masks`` (sb3-contrib's convention)."""
    try:
        env.get_wrapper_attr("action_masks")
    except AttributeError:
        return False
    return True


def _need_discrete(env: gym.Env, name: str) -> Any:
    u: Any = env.unwrapped
    if getattr(u, "config", None) is None or u.config.action_mode != "pick_place_discrete":
        raise PolicyError(f"policy {name!r} needs action_mode 'pick_place_discrete'")
    return u


def _openloop(base: dict[str, Any]) -> Policy:
    def factory(env: gym.Env) -> Predict:
        u = _need_discrete(env, "openloop")
        env.reset(seed=OPENLOOP_TRAIN_SEED)
        seq = []
        for i in range(len(env.get_wrapper_attr("task_spec").slots)):
            a = u.expert_action(i, i)
            seq.append(a)
            *_, term, trunc, _ = env.step(a)
            if term or trunc:
                break
        step = [0]

        def predict(obs: dict[str, Any], start: bool) -> np.ndarray:
            del obs
            step[0] = 0 if start else step[0] + 1
            return seq[step[0] % len(seq)]

        return predict

    return Policy("openloop", dict(base), factory)


def _identity(base: dict[str, Any]) -> Policy:
    def factory(env: gym.Env) -> Predict:
        _need_discrete(env, "identity")
        k = len(env.get_wrapper_attr("task_spec").slots)
        step = [0]

        def predict(obs: dict[str, Any], start: bool) -> np.ndarray:
            del obs
            step[0] = 0 if start else step[0] + 1
            i = step[0] % k
            return np.array([i, i, 0], np.int64)

        return predict

    return Policy("identity", dict(base), factory)


def run_config(model_path: Path) -> dict[str, Any]:
    """The ``train_config.yaml`` of a run (beside the model or one folder up), or {}."""
    for folder in (model_path.parent, model_path.parent.parent):
        cfg = folder / "train_config.yaml"
        if cfg.is_file():
            data = yaml.safe_load(cfg.read_text(encoding="utf-8"))
            return data if isinstance(data, dict) else {}
    return {}


def checkpoint_label(model_path: Path) -> str:
    """A short name of a checkpoint: run folder (and its parent for ``seed_<k>``), file stem."""
    run = model_path.parent.parent if model_path.parent.name == "checkpoints" else model_path.parent
    name = f"{run.parent.name}/{run.name}" if run.name.startswith("seed_") else run.name
    return name if model_path.name == "model.zip" else f"{name}/{model_path.stem}"


def load_model(model_path: Path, algo: str = "") -> Any:
    """Load an SB3 model on the CPU (``algo`` from its run, else each of `ALGORITHMS`).

    Raises:
        PolicyError: No algorithm loads it.
    """
    from agents.learning.algorithms import algorithm_class  # noqa: PLC0415

    names = [algo] if algo else list(ALGORITHMS)
    reason = ""
    for name in names:
        try:
            return algorithm_class(name).load(str(model_path), device="cpu")
        except (ValueError, KeyError, RuntimeError, AttributeError, OSError, EOFError) as exc:
            reason = f"{type(exc).__name__}: {' '.join(str(exc).split())[:200]}"
        except zipfile.BadZipFile as exc:
            reason = f"not a complete zip file ({exc})"
    raise PolicyError(f"cannot load {model_path} with any of {names} ({reason})")


def _trained(base: dict[str, Any], model_path: Path) -> Policy:
    run = run_config(model_path)
    run_env = dict(run.get("env") or {})
    env_kwargs = {**base, **{k: run_env[k] for k in SPACE_KEYS if k in run_env}}
    label = checkpoint_label(model_path)

    def factory(env: gym.Env) -> Predict:
        model = load_model(model_path, str(run.get("algo", "")))
        check_spaces(label, env, model.observation_space, model.action_space, sb3_view=True)
        # A maskable model (sb3-contrib's MaskablePPO) plays with the env's action masks.
        masked = "action_masks" in inspect.signature(model.predict).parameters

        def predict(obs: dict[str, Any], start: bool) -> np.ndarray:
            del start
            kw = {"action_masks": env.get_wrapper_attr("action_masks")()} if masked else {}
            return np.asarray(model.predict(obs, deterministic=True, **kw)[0])

        return predict

    wrap: Callable[[gym.Env], gym.Env] | None = None
    if run.get("flatten_actions"):
        wrap = FlatDiscreteActions
    if run.get("residual_scale"):  # residual RL: the scripted controller is part of the policy
        from agents.learning.residual import ResidualExpertActions  # noqa: PLC0415

        scale = float(run["residual_scale"])

        def wrap(env: gym.Env) -> gym.Env:
            return ResidualExpertActions(env, scale)

    return Policy(label, env_kwargs, factory, wrap)


def _clone(base: dict[str, Any], path: Path) -> Policy:
    """A ``.pt`` policy: a camera policy (by the file's ``kind``) or a behaviour clone."""
    from agents.camera.crop_scorer import KIND, read_policy_file  # noqa: PLC0415
    from agents.equivariant.policy import KIND as EQUIVARIANT_KIND  # noqa: PLC0415
    from agents.errors import AgentError  # noqa: PLC0415

    allowed = (
        "a camera policy (apps.bc.camera), an equivariant pixel policy "
        "(benchmarks.learned.equivariant) or a behaviour clone (apps.bc.decision) .pt file"
    )
    if not path.is_file():
        raise PolicyError(f"unknown policy {str(path)!r}: no such file; a .pt policy is {allowed}")
    try:
        kind = read_policy_file(path).get("kind")
    except AgentError as exc:
        raise PolicyError(f"policy {str(path)!r}: {exc}; a .pt policy is {allowed}") from exc
    if kind in (KIND, EQUIVARIANT_KIND):
        return _camera(base, path, kind)
    label = checkpoint_label(path)
    from agents.learning.decision_bc import BCPolicy  # noqa: PLC0415

    overrides = BCPolicy(path).env_overrides  # an objects clone plays on objects rows

    def factory(env: gym.Env) -> Predict:
        clone = BCPolicy(path)
        check_spaces(label, env, None, clone.action_space)

        def predict(obs: dict[str, Any], start: bool) -> np.ndarray:
            del start
            return clone.predict(obs)[0]

        return predict

    return Policy(label, {**base, **overrides}, factory)


def _camera(base: dict[str, Any], path: Path, kind: str) -> Policy:
    """A camera policy: ``rgb`` observations at its image size, in the env's action mode.

    ``kind`` says which: the crop scorer (`agents.camera.crop_scorer`) or the equivariant
    policy (`agents.equivariant.policy`, played with the env's action masks). In
    ``pick_place`` the choice is placed at the poses of the figure fit
    (`agents.camera.continuous.ContinuousCameraPolicy`, bundled fit settings); its label says
    so when the base env asks for that mode, so its episodes never mix with the discrete ones.
    """
    from agents.camera.crop_scorer import CameraPolicy  # noqa: PLC0415
    from agents.equivariant.policy import KIND as EQUIVARIANT_KIND  # noqa: PLC0415
    from agents.equivariant.policy import EquivariantPolicy  # noqa: PLC0415

    scorer: Any = (EquivariantPolicy if kind == EQUIVARIANT_KIND else CameraPolicy).load(path)
    env_kwargs = {**base, "obs_mode": "rgb", "image_size": list(scorer.image_size)}
    label = checkpoint_label(path)
    label += "@pick_place" if base.get("action_mode") == "pick_place" else ""

    def factory(env: gym.Env) -> Predict:
        spec = [env.get_wrapper_attr("task_spec")]
        mode = spec[0].action_mode
        player: Any = scorer
        masked = False
        if mode == "pick_place":
            from agents.camera.continuous import ContinuousCameraPolicy, load_fit_config  # noqa: PLC0415

            player = ContinuousCameraPolicy(scorer, load_fit_config())
        elif mode not in CAMERA_ACTION_MODES:
            raise PolicyError(
                f"policy {label!r} is a camera policy: it plays action_mode "
                f"{' or '.join(repr(m) for m in CAMERA_ACTION_MODES)}, not {mode!r}"
            )
        else:
            masked = kind == EQUIVARIANT_KIND and _has_masks(env)

        def predict(obs: dict[str, Any], start: bool) -> np.ndarray:
            if start:
                spec[0] = env.get_wrapper_attr("task_spec")
                if hasattr(player, "reset"):
                    player.reset()
            if masked:
                masks = env.get_wrapper_attr("action_masks")()
                return np.asarray(player.predict(obs, spec[0], masks)[0])
            return np.asarray(player.predict(obs, spec[0])[0])

        return predict

    return Policy(label, env_kwargs, factory)


def _user(base: dict[str, Any], spec: str) -> Policy:
    module_name, _, attr = spec.partition(":")
    try:
        obj: Any = getattr(importlib.import_module(module_name), attr)
    except (ImportError, AttributeError) as exc:
        raise PolicyError(f"cannot import policy {spec!r}: {exc}") from exc

    def factory(env: gym.Env) -> Predict:
        is_class = inspect.isclass(obj)
        make: Callable[[gym.Env], Any] = obj
        target: Any = make(env) if is_class else obj
        check_spaces(
            spec,
            env,
            getattr(target, "observation_space", None),
            getattr(target, "action_space", None),
        )
        call = target.predict if hasattr(target, "predict") else target
        if not callable(call):
            raise PolicyError(f"policy {spec!r} is neither callable nor has a predict method")

        def predict(obs: dict[str, Any], start: bool) -> np.ndarray:
            del start
            out = call(obs)
            return np.asarray(out[0] if isinstance(out, tuple) else out)

        return predict

    return Policy(spec, dict(base), factory)


def make_policy(
    spec: str,
    base: dict[str, Any],
    scripted_image_size: tuple[int, int] = SCRIPTED_IMAGE_SIZE,
    calibrate: bool = True,
) -> Policy:
    """Resolve one policy name (see the module docstring), with optional ``@KEY=VALUE`` overrides.

    Raises:
        PolicyError: A name that is none of the accepted forms, or a malformed override.
    """
    name, _, extra = spec.partition("@")
    overrides = parse_pairs(extra.split(",")) if extra else {}
    builtins: dict[str, Callable[[], Policy]] = {
        "scripted": lambda: _scripted(base, scripted_image_size, calibrate),
        "random": lambda: _random(base),
        "openloop": lambda: _openloop(base),
        "identity": lambda: _identity(base),
    }
    if name in builtins:
        pol = builtins[name]()
    elif name.endswith(".pt"):
        pol = _clone(base, Path(name))
    elif name.endswith(".zip") or Path(name).is_file():
        if not Path(name).is_file():
            raise PolicyError(
                f"unknown policy {name!r}: no such checkpoint; use one of {sorted(builtins)}, "
                "a model .zip path or module:callable"
            )
        pol = _trained(base, Path(name))
    elif ":" in name:
        pol = _user(base, name)
    else:
        raise PolicyError(
            f"unknown policy {name!r}: use one of {sorted(builtins)}, a model .zip path or "
            "module:callable"
        )
    if overrides:
        label = spec if name in builtins else f"{pol.label}@{extra}"
        pol = replace(pol, label=label, env_kwargs={**pol.env_kwargs, **overrides})
    return pol


def make_policies(
    names: Sequence[str],
    base: dict[str, Any],
    scripted_image_size: tuple[int, int] = SCRIPTED_IMAGE_SIZE,
    calibrate: bool = True,
) -> list[Policy]:
    """`make_policy` for each name."""
    return [make_policy(n, base, scripted_image_size, calibrate) for n in names]


def parse_pairs(pairs: Sequence[str]) -> dict[str, Any]:
    """``KEY=VALUE`` strings -> a dict (values parsed as YAML).

    Raises:
        PolicyError: A string without ``=``.
    """
    out: dict[str, Any] = {}
    for pair in pairs:
        if "=" not in pair:
            raise PolicyError(f"env overrides want KEY=VALUE, got {pair!r}")
        key, value = pair.split("=", 1)
        out[key.strip()] = yaml.safe_load(value)
    return out


__all__ = [
    "CAMERA_ACTION_MODES",
    "SCRIPTED_IMAGE_SIZE",
    "SPACE_KEYS",
    "Policy",
    "PolicyError",
    "Predict",
    "check_spaces",
    "load_model",
    "make_policies",
    "make_policy",
    "parse_pairs",
    "run_config",
]
