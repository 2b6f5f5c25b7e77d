"""benchmarks: aggregation of small fake benchmark JSON files into one table."""

from __future__ import annotations

import json

from benchmarks.figures import fig
from benchmarks.table import BENCHES, collect, command, main, table


def _write(folder, name, data):
    (folder / name).write_text(json.dumps(data))


def _fakes(folder):
    _write(
        folder,
        "bench_qshape.json",
        {
            "tiles": 100,
            "describe_s": 0.5,
            "describe_many_s": 0.1,
            "assign_optimal": {"seconds": 2.0, "assigned": 100, "correct_class": 100},
            "assign_greedy": {"seconds": 0.2, "assigned": 100, "correct_class": 99},
            "speedup_vs_paper_greedy": 4.0,
        },
    )
    _write(
        folder,
        "bench_env.json",
        {
            "targets": {
                "kinematic_pick_place_steps_per_s": {"value": 600.0, "target": 500.0},
                "peak_rss_mb": {"value": 700.0, "target": 600.0},
            },
            "async": {"speedup": 1.5},
        },
    )
    _write(
        folder,
        "eval.json",
        {
            "rows": [
                {
                    "policy": "scripted",
                    "success_rate": 1.0,
                    "correct": 6.0,
                    "tiles_per_min": 26.0,
                    "wall_s_per_tile": 0.2,
                },
                {
                    "policy": "random",
                    "success_rate": 0.0,
                    "correct": 0.5,
                    "tiles_per_min": 2.0,
                    "wall_s_per_tile": 0.1,
                },
                {
                    "policy": "ppo",
                    "success_rate": 0.5,
                    "correct": 4.0,
                    "tiles_per_min": 20.0,
                    "wall_s_per_tile": 0.01,
                },
            ]
        },
    )


def test_collect_checks_targets(tmp_path):
    _fakes(tmp_path)
    figures, sources = collect(BENCHES, tmp_path)
    by = {(f.group, f.name): f for f in figures}
    assert by[("qshape", "describe 100 tiles (describe_many)")].passed is True
    assert by[("qshape", "describe 100 tiles (one by one)")].passed is None
    assert by[("qshape", "assign 100 x 100 optimal")].passed is False
    assert by[("env", "kinematic pick place steps per s")].passed is True
    assert by[("env", "peak rss mb")].passed is False
    assert by[("learned", "scripted tiles/min (sim)")].passed is True
    assert by[("learned", "ppo correct/episode vs random")].passed is True
    assert by[("learned", "ppo correct/episode vs random")].target == "> 0.5"
    missing = [f for f in figures if f.group == "cell"]
    assert len(missing) == 1 and missing[0].value is None and "missing" in sources["cell"]
    text = table(figures)
    assert "| qshape | assign 100 x 100 optimal | 2 | s | <= 1 | FAIL |" in text


def test_main_from_json_writes_report(tmp_path, capsys):
    _fakes(tmp_path)
    report = main(["--from-json", "--out-dir", str(tmp_path)])
    saved = json.loads((tmp_path / "bench.json").read_text())
    assert saved["date"] and saved["machine"]["cpus"] and saved["mode"] == "from-json"
    load = saved["machine"]["load"]
    for moment in ("start", "end"):
        assert 1 <= load[moment]["cpus_usable"] <= saved["machine"]["cpus"]
        assert len(load[moment]["load_average"]) == 3
    assert saved["summary"] == report["summary"]
    assert "qshape: assign 100 x 100 optimal" in saved["summary"]["failed"]
    assert (tmp_path / "bench.md").is_file()
    assert "targets met" in capsys.readouterr().out


def test_fig_and_commands(tmp_path):
    assert fig("g", "n", None, "s", "<=", 1.0).passed is None
    assert fig("g", "n", 3, "s").target == ""
    assert fig("g", "n", True, "", "==", 1.0).passed is True
    by = {b.name: b for b in BENCHES}
    assert command(by["main"], tmp_path, False, None) is None
    cmd = command(by["planner"], tmp_path, True, None)
    assert cmd is not None and cmd[2] == "benchmarks.motion.planner" and "--quick" in cmd
    env_cmd = command(by["env"], tmp_path, False, None)
    assert env_cmd is not None and "--out" not in env_cmd
    ev = command(by["learned"], tmp_path, False, tmp_path / "run" / "model.zip")
    assert ev is not None and str(tmp_path / "run" / "model.zip") in ev
