"""Reading the episode logs a training run writes: SB3 ``Monitor`` CSVs under ``monitor/``.

`apps.train` wraps every env in SB3's ``Monitor`` (one ``<env index>.monitor.csv`` per env:
a ``#``-prefixed JSON line, a header, then one row per finished episode with its return
``r``, length ``l``, wall time ``t`` since the start and the logged info keys such as
``is_success``, ``filled`` and ``cpu_s``). The run's summary (`apps.train`), the sweep's
training curves (`apps.results.sweep_summary`) and the CPU-minute curves
(`apps.results.plot_curves`) read them through `monitor_episodes`.
"""

from __future__ import annotations

from pathlib import Path

SUCCESS_VALUES = ("True", "1", "1.0")
"""How SB3 writes a true ``is_success``."""


def monitor_episodes(monitor_dir: Path) -> list[dict[str, str]]:
    """Every finished episode of every env's CSV in ``monitor_dir``, as column -> text.

    Files in name order, rows in file order; a file without episode rows adds none.
    """
    episodes: list[dict[str, str]] = []
    for path in sorted(monitor_dir.glob("*.monitor.csv")):
        lines = path.read_text(encoding="utf-8").splitlines()[1:]  # past the JSON line
        if len(lines) < 2:
            continue
        head = lines[0].split(",")
        episodes.extend(dict(zip(head, line.split(","), strict=False)) for line in lines[1:])
    return episodes


def succeeded(episode: dict[str, str]) -> float:
    """1.0 if the episode's ``is_success`` is true, else 0.0 (also when not logged)."""
    return 1.0 if episode.get("is_success", "False") in SUCCESS_VALUES else 0.0


__all__ = ["SUCCESS_VALUES", "monitor_episodes", "succeeded"]
