"""apps.results.monitor_log: the Monitor CSVs of a run as episodes, every env's file in order."""

from __future__ import annotations

from apps.results.monitor_log import monitor_episodes, succeeded


def test_episodes_of_every_env_file_and_their_success(tmp_path) -> None:
    head = '#{"t_start": 0.0, "env_id": "MosaicDecision6-v0"}\nr,l,t,is_success,filled\n'
    (tmp_path / "0.monitor.csv").write_text(head + "1.5,6,2.0,True,1.0\n-0.5,12,4.0,False,0.5\n")
    (tmp_path / "1.monitor.csv").write_text(head)  # an env that finished no episode
    (tmp_path / "2.monitor.csv").write_text(head + "0.0,12,3.0,1.0,0.8\n")
    (tmp_path / "notes.txt").write_text("not a monitor file\n")
    eps = monitor_episodes(tmp_path)
    assert [ep["l"] for ep in eps] == ["6", "12", "12"]
    assert [succeeded(ep) for ep in eps] == [1.0, 0.0, 1.0]
    assert eps[2]["filled"] == "0.8"
    assert succeeded({"r": "1.0"}) == 0.0  # not logged: not a success
    assert monitor_episodes(tmp_path / "missing") == []
