"""apps.evaluate: table rows for scripted and random on 2 seeds, seed parsing, outputs."""

from __future__ import annotations

import json

import pytest

from apps.evaluate import (
    COLUMNS,
    EPISODES_FILE,
    EpisodeResult,
    EvaluateError,
    aggregate,
    evaluate_policy_set,
    load_env_overrides,
    make_policies,
    markdown_table,
    parse_seeds,
    write_outputs,
)
from apps.evaluate_results import episode_metrics

BASE = {
    "design": "paper_mixed",
    "max_slots": 2,
    "execution": "kinematic",
    "action_mode": "pick_place_discrete",
    "obs_mode": "state",
}


@pytest.fixture(scope="module")
def evaluated():
    pols = make_policies(["scripted", "random"], BASE, calibrate=False)
    return evaluate_policy_set(pols, [1000, 1001])


def test_rows_have_the_keys(evaluated, tmp_path):
    rows, episodes = evaluated
    assert [r.policy for r in rows] == ["scripted", "random"]
    for r in rows:
        for key, _, _ in COLUMNS:
            assert hasattr(r, key)
        assert r.episodes == 2 and r.slots == 2
        assert 0.0 <= r.success_rate <= 1.0
    scripted = rows[0]
    assert scripted.success_rate == 1.0 and scripted.correct == 2 and scripted.misplaced == 0
    assert scripted.tiles_per_min > 0 and scripted.wall_s_per_tile is not None
    assert scripted.env["action_mode"] == "pick_place"  # scripted gets its own action mode
    assert rows[1].env["action_mode"] == "pick_place_discrete"
    assert [e.seed for e in episodes["random"]] == [1000, 1001]
    report = write_outputs(rows, episodes, [1000, 1001], tmp_path)
    assert (tmp_path / "eval.png").stat().st_size > 0
    saved = json.loads((tmp_path / "eval.json").read_text())
    assert saved["rows"][0]["policy"] == "scripted" and report["seeds"] == [1000, 1001]
    assert "| scripted |" in markdown_table(rows)


def test_one_tiles_per_min_definition(evaluated):
    """A row's tiles/min is the mean of its episodes' protocol figures (what the sweep averages)."""
    rows, episodes = evaluated
    for r in rows:
        eps = episodes[r.policy]
        per_episode = [episode_metrics(e).tiles_per_min for e in eps]
        assert r.tiles_per_min == pytest.approx(sum(per_episode) / len(eps))
        for e in eps:  # failed episodes are measured over at least the horizon (2 x 5 s)
            assert e.span_s == (e.sim_s if e.success else max(e.sim_s, 10.0))
    fast = EpisodeResult("p", 0, "d", True, 2, 2, 0, 0, 0, 0, 2, 5.0, 5.0, 1.0, 0.0)
    failed = EpisodeResult("p", 1, "d", False, 0, 2, 0, 0, 0, 0, 2, 3.0, 20.0, 1.0, 0.0)
    row = aggregate("p", [fast, failed], {})
    assert row.tiles_per_min == pytest.approx(12.0)  # (24 + 0) / 2, not 60 * 2 / 25 = 4.8


def test_random_is_reproducible(evaluated):
    _, episodes = evaluated
    pols = make_policies(["random"], BASE)
    _, again = evaluate_policy_set(pols, [1000, 1001])
    first = [(e.correct, e.misplaced, e.episode_return) for e in episodes["random"]]
    assert first == [(e.correct, e.misplaced, e.episode_return) for e in again["random"]]


def test_seeds_and_bad_input(tmp_path):
    assert parse_seeds(["1000-1003"]) == [1000, 1001, 1002, 1003]
    assert parse_seeds(["1,2", "5"]) == [1, 2, 5]
    for bad in (["x"], ["5-3"], [""]):
        with pytest.raises(EvaluateError):
            parse_seeds(bad)
    with pytest.raises(EvaluateError, match="KEY=VALUE"):
        load_env_overrides(None, ["max_slots"])
    with pytest.raises(EvaluateError, match="unknown"):
        load_env_overrides(None, ["max_slot=2"])
    assert load_env_overrides("configs/train/tiny.yaml", ["max_slots=1"])["max_slots"] == 1
    pols = make_policies(["scripted@execution=dynamic,belt_speed=0.1", "random"], BASE)
    assert pols[0].label == "scripted@execution=dynamic,belt_speed=0.1"
    assert pols[0].env_kwargs["execution"] == "dynamic"
    assert pols[0].env_kwargs["belt_speed"] == 0.1
    assert pols[1].env_kwargs["execution"] == "kinematic"
    with pytest.raises(EvaluateError, match="KEY=VALUE"):
        make_policies(["random@oops"], BASE)
    with pytest.raises(EvaluateError, match="scripted"):
        make_policies([str(tmp_path / "missing.zip")], BASE)


def test_a_rerun_never_takes_another_policys_episodes(tmp_path):
    log = tmp_path / EPISODES_FILE
    evaluate_policy_set(make_policies(["random"], BASE), [1000, 1001], log=log)
    _, episodes = evaluate_policy_set(make_policies(["identity"], BASE), [1000, 1001], log=log)
    assert [(e.policy, e.seed) for e in episodes["identity"]] == [
        ("identity", 1000),
        ("identity", 1001),
    ]
    logged = [(e["policy"], e["seed"]) for e in map(json.loads, log.read_text().splitlines())]
    assert logged == [("random", 1000), ("random", 1001), ("identity", 1000), ("identity", 1001)]
    # And a rerun of both plays nothing again.
    _, again = evaluate_policy_set(
        make_policies(["random", "identity"], BASE), [1000, 1001], log=log
    )
    assert len(log.read_text().splitlines()) == 4
    assert [e.policy for e in again["random"]] == ["random", "random"]


def test_a_rerun_with_other_env_keys_never_takes_the_logged_episodes(tmp_path):
    """The same policy and seeds under other env overrides (another task, rotation frame,
    camera) are other episodes: this test failed when a log matched on label and seed only,
    and a second evaluation into the same folder quietly reported the first one's figures."""
    log = tmp_path / EPISODES_FILE
    evaluate_policy_set(make_policies(["random"], BASE), [1000, 1001], log=log)
    other = {**BASE, "rotation_frame": "slot"}
    _, episodes = evaluate_policy_set(make_policies(["random"], other), [1000, 1001], log=log)
    assert len(log.read_text().splitlines()) == 4  # both played again, not taken from the log
    envs_logged = {e["env"] for e in map(json.loads, log.read_text().splitlines())}
    assert len(envs_logged) == 2
    assert [e.seed for e in episodes["random"]] == [1000, 1001]


def test_seeds_given_with_a_task_keep_its_protocol(tmp_path):
    from apps.evaluate import main, task_protocol  # noqa: PLC0415

    _, proto = task_protocol("MosaicDecision6-v0")
    args = ["--policies", "random", "--task", "MosaicDecision6-v0", "--seeds", "1000"]
    report = main([*args, "--out", str(tmp_path), "--quiet"])
    assert list(report["protocol"]["seeds"]) == [1000]
    assert report["protocol"]["max_steps"] == proto.max_steps
    assert report["protocol"]["horizon_s"] == proto.horizon_s > 0
