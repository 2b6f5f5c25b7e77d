"""The evaluation protocol: per-episode metrics and their aggregation over training seeds.

Per episode (`EpisodeMetrics.of`, from the env's final ``info``: its `envs.task.Evaluation`,
the one record of an episode, and the simulated time):

- ``success``: every slot filled correctly;
- ``filled``: fraction of the slots filled correctly;
- ``misplaced``, ``dropped`` (drop events), ``lost``, ``stranded`` (real tiles fed that lie
  out of every other state: beside the mesh, tilted over its edge), ``left`` (real tiles never
  placed: still on the input belt, held or waiting to be fed at the end), counts;
- ``tiles_per_min``: correct tiles per simulated minute (`envs.task.Evaluation.tiles_per_min`,
  the one definition), measured to completion for a successful episode and over
  ``max(episode time, horizon)`` otherwise, so stopping early after a few tiles cannot look as
  fast as finishing (the horizon is the task's ``horizon_s``). Over several episodes it is the
  mean of the episodes' figures (each episode weighs the same), as every other metric.

Aggregation (`aggregate_runs`): each training run (seed) is scored by its mean over the held-out
episodes; a result over runs is the interquartile mean (IQM) with a 95 % stratified-bootstrap
confidence interval (``rliable``).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from agents.errors import AgentError
from envs.task import Evaluation

METRICS = (
    "success",
    "filled",
    "misplaced",
    "dropped",
    "lost",
    "stranded",
    "left",
    "tiles_per_min",
)
"""Metric names of `EpisodeMetrics` aggregated over runs."""
BOOTSTRAP_REPS = 2000
"""Bootstrap resamples of the confidence intervals."""
CONFIDENCE = 0.95
"""Confidence level of the intervals."""


class TileCounts(Protocol):
    """What an episode's outcome counts (`envs.task.Evaluation` and recorded results have it)."""

    @property
    def success(self) -> bool: ...  # noqa: D102
    @property
    def correct(self) -> int: ...  # noqa: D102
    @property
    def slots(self) -> int: ...  # noqa: D102
    @property
    def misplaced(self) -> int: ...  # noqa: D102
    @property
    def dropped(self) -> int: ...  # noqa: D102
    @property
    def lost(self) -> int: ...  # noqa: D102
    @property
    def stranded(self) -> int: ...  # noqa: D102


@dataclass(frozen=True)
class EpisodeMetrics:
    """The protocol's metrics of one episode.

    Attributes:
        success: 1.0 when every slot was filled correctly, else 0.0.
        filled: Fraction of slots filled correctly, in [0, 1].
        misplaced: Real tiles on the mesh filling no slot [count].
        dropped: Drop events (the pad lost a tile in transit) [count].
        lost: Tiles lost off the input belt [count].
        stranded: Real tiles out of every other state (beside the mesh, tilted) [count].
        left: Real tiles never placed: on the input belt, held or waiting at the end [count].
        tiles_per_min: Correct tiles per simulated minute (see the module docstring).
        sim_s: Simulated episode time [s].
        span_s: Time the throughput is measured over [s]: ``sim_s`` for a successful
            episode, ``max(sim_s, horizon)`` otherwise (the one home of that rule).
    """

    success: float
    filled: float
    misplaced: float
    dropped: float
    lost: float
    stranded: float
    left: float
    tiles_per_min: float
    sim_s: float
    span_s: float

    @staticmethod
    def of(info: Mapping[str, Any], horizon_s: float) -> EpisodeMetrics:
        """Metrics from an episode's final ``info`` (``evaluation`` and ``sim_time``).

        Args:
            info: The last step's info dict.
            horizon_s: Throughput horizon of a failed episode [s].
        """
        return EpisodeMetrics.from_evaluation(
            Evaluation.from_info(info), float(info["sim_time"]), horizon_s
        )

    @staticmethod
    def from_evaluation(ev: Evaluation, sim_s: float, horizon_s: float) -> EpisodeMetrics:
        """Metrics of an episode's final evaluation after ``sim_s`` simulated seconds.

        Args:
            ev: The evaluation of the episode's last step.
            sim_s: Simulated episode time [s].
            horizon_s: Throughput horizon of a failed episode [s].
        """
        return EpisodeMetrics.from_counts(
            ev,
            left=ev.on_input + ev.held + ev.waiting,  # never placed
            tiles_per_min=ev.tiles_per_min(sim_s, horizon_s),
            sim_s=sim_s,
            span_s=ev.throughput_span(sim_s, horizon_s),
        )

    @staticmethod
    def from_counts(
        counts: TileCounts, *, left: float, tiles_per_min: float, sim_s: float, span_s: float
    ) -> EpisodeMetrics:
        """The one construction of the metrics from an episode's tile counts.

        Args:
            counts: The episode's outcome (an `envs.task.Evaluation`, an evaluation record).
            left: Tiles never placed.
            tiles_per_min: Placed-and-correct tiles per simulated minute.
            sim_s: Simulated episode time [s].
            span_s: The span the throughput is measured over [s].
        """
        return EpisodeMetrics(
            success=float(counts.success),
            filled=counts.correct / max(counts.slots, 1),
            misplaced=float(counts.misplaced),
            dropped=float(counts.dropped),
            lost=float(counts.lost),
            stranded=float(counts.stranded),
            left=float(left),
            tiles_per_min=tiles_per_min,
            sim_s=sim_s,
            span_s=span_s,
        )


@dataclass(frozen=True)
class Estimate:
    """A point estimate over runs with its confidence interval.

    Attributes:
        iqm: Interquartile mean over runs.
        lo: Lower bound of the 95 % stratified-bootstrap interval.
        hi: Upper bound.
        runs: Number of runs.
    """

    iqm: float
    lo: float
    hi: float
    runs: int

    def text(self, fmt: str = "{:.2f}") -> str:
        """``iqm [lo, hi]`` (a single run: just the value)."""
        if self.runs < 2 or self.lo == self.hi:
            return fmt.format(self.iqm)
        return f"{fmt.format(self.iqm)} [{fmt.format(self.lo)}, {fmt.format(self.hi)}]"


def run_score(episodes: Sequence[EpisodeMetrics]) -> dict[str, float]:
    """Mean of every metric over one run's held-out episodes.

    Raises:
        AgentError: No episodes.
    """
    if not episodes:
        raise AgentError("a run needs at least one evaluated episode")
    return {m: float(np.mean([getattr(e, m) for e in episodes])) for m in METRICS}


def iqm_ci(values: Sequence[float], seed: int = 0) -> Estimate:
    """IQM of per-run values with a 95 % stratified-bootstrap CI (``rliable``).

    Args:
        values: One value per run (training seed).
        seed: Seed of the bootstrap.
    """
    x = np.asarray(values, float).reshape(-1, 1)
    if len(x) == 0:
        raise AgentError("no runs to aggregate")
    from rliable import library as rly  # noqa: PLC0415 - heavy import
    from rliable import metrics  # noqa: PLC0415

    point = float(metrics.aggregate_iqm(x))
    if len(x) < 2:
        return Estimate(point, point, point, 1)
    with warnings.catch_warnings():  # arch: RandomState is deprecated (still supported)
        warnings.simplefilter("ignore", FutureWarning)
        _, cis = rly.get_interval_estimates(
            {"r": x},
            lambda s: np.array([metrics.aggregate_iqm(s)]),
            reps=BOOTSTRAP_REPS,
            confidence_interval_size=CONFIDENCE,
            random_state=np.random.RandomState(seed),
        )
    lo, hi = (float(v) for v in np.asarray(cis["r"]).ravel()[:2])
    return Estimate(point, lo, hi, len(x))


def aggregate_runs(runs: Sequence[Mapping[str, float]]) -> dict[str, Estimate]:
    """IQM and CI of every metric over runs (each a `run_score` dict)."""
    # Results written before a metric existed count it as 0 (``left`` came after ``stranded``).
    return {m: iqm_ci([r.get(m, 0.0) for r in runs]) for m in METRICS}


__all__ = [
    "METRICS",
    "EpisodeMetrics",
    "Estimate",
    "TileCounts",
    "aggregate_runs",
    "iqm_ci",
    "run_score",
]
