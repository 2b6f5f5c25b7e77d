"""agents.protocol: the throughput horizon of a failed episode and the IQM over runs."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from scipy import stats

from agents.protocol import METRICS, EpisodeMetrics, aggregate_runs, iqm_ci
from apps.evaluate import ENV_ID, aggregate, load_env_overrides, run_episode
from envs.task import Evaluation


def _info(success: bool, correct: int, slots: int, sim_time: float) -> dict:
    left = slots - correct
    ev = Evaluation(
        success=success,
        failure=not success,
        correct=correct,
        misplaced=0,
        dropped=0,
        stranded=0,
        lost=0,
        fed=slots,
        waiting=0,
        on_input=left,
        held=0,
        dropped_tiles=0,
        lost_tiles=0,
        rejected=0,
        distractors_placed=0,
        slots=slots,
        slot_filled=(True,) * correct + (False,) * left,
        placeable=left,
        position_error_mm=None,
        position_error_mm_max=None,
        yaw_error_deg=None,
        yaw_error_deg_max=None,
    )
    return {"evaluation": ev.as_dict(), "sim_time": sim_time}


def test_a_failed_episode_is_measured_over_the_horizon() -> None:
    # 2 correct tiles in 6 simulated seconds, episode failed, horizon 20 s: 6 tiles/min.
    failed = EpisodeMetrics.of(_info(False, 2, 4, 6.0), horizon_s=20.0)
    assert failed.span_s == 20.0 and failed.tiles_per_min == pytest.approx(6.0)
    # Running past the horizon: the episode's own time.
    late = EpisodeMetrics.of(_info(False, 2, 4, 30.0), horizon_s=20.0)
    assert late.span_s == 30.0 and late.tiles_per_min == pytest.approx(4.0)
    # A finished mosaic is measured to completion, however short.
    done = EpisodeMetrics.of(_info(True, 4, 4, 6.0), horizon_s=20.0)
    assert done.span_s == 6.0 and done.tiles_per_min == pytest.approx(40.0)


def test_evaluate_measures_a_failed_episode_over_the_horizon() -> None:
    env = gym.make(ENV_ID, **load_env_overrides("tiny"))
    try:
        space = env.action_space
        space.seed(0)
        horizon = 1000.0
        ep = run_episode(env, lambda obs, start: space.sample(), 1000, 1, horizon)
    finally:
        env.close()
    assert not ep.success and ep.sim_s < horizon
    assert ep.span_s == horizon  # stopping after one step does not make it fast
    row = aggregate("random", [ep], {})
    assert row.tiles_per_min == pytest.approx(60.0 * ep.correct / horizon)


def test_iqm_ci_over_runs() -> None:
    runs = [0.1, 0.9, 0.5, 0.4, 0.6, 0.3, 0.7, 0.2]
    est = iqm_ci(runs)
    assert est.runs == 8
    assert est.iqm == pytest.approx(stats.trim_mean(runs, 0.25))
    assert est.lo < est.iqm < est.hi  # an interval, not a point
    assert 0.1 <= est.lo and est.hi <= 0.9
    one = iqm_ci([0.5])
    assert (one.iqm, one.lo, one.hi, one.runs) == (0.5, 0.5, 0.5, 1)


def test_aggregate_runs_takes_one_value_per_run_and_metric() -> None:
    rng = np.random.default_rng(5)
    runs = [
        {m: float(v) for m, v in zip(METRICS, rng.uniform(0, 1, len(METRICS)), strict=True)}
        for _ in range(5)
    ]
    est = aggregate_runs(runs)
    assert set(est) == set(METRICS)
    for m in METRICS:
        values = [r[m] for r in runs]
        assert est[m].runs == 5
        assert est[m].iqm == pytest.approx(stats.trim_mean(values, 0.25))
        assert est[m].lo <= est[m].iqm <= est[m].hi and est[m].lo < est[m].hi
