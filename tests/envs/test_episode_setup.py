"""Episode set-up's layout policy (`envs.episode_setup`): retries, the feed fallback, feed modes."""

from __future__ import annotations

from typing import get_args

import pytest

from agents.scripted.config import RunConfig
from envs.cell.config import FEED_MODES, FeedMode, TileConfig
from envs.env_config import FEEDS
from envs.episode_setup import FALLBACK_FEED, retry_layout, with_feed_fallback
from envs.errors import CellError, LayoutError
from envs.task_spec import FeedMode as SpecFeedMode


def _flaky(fails: int, error: type[Exception]):  # noqa: ANN202 - a test double
    calls: list[int] = []

    def draw(k: int) -> int:
        calls.append(k)
        if len(calls) <= fails:
            raise error(f"draw {k} jammed")
        return k

    return draw, calls


def test_a_jammed_draw_is_redrawn_until_one_fits() -> None:
    draw, calls = _flaky(2, LayoutError)
    assert retry_layout(draw, 5) == 2 and calls == [0, 1, 2]


def test_the_last_error_is_raised_when_no_draw_fits() -> None:
    draw, calls = _flaky(9, LayoutError)
    with pytest.raises(LayoutError, match="draw 2 jammed"):
        retry_layout(draw, 3)
    assert calls == [0, 1, 2]
    with pytest.raises(LayoutError, match="tries must be >= 1"):
        retry_layout(draw, 0)


def test_a_deterministic_misfit_is_raised_at_once_unless_asked() -> None:
    draw, calls = _flaky(1, CellError)
    with pytest.raises(CellError, match="draw 0"):
        retry_layout(draw, 5)
    assert calls == [0]
    draw, calls = _flaky(1, CellError)
    assert retry_layout(draw, 5, retry_on=CellError) == 1  # the reset's policy


def test_feed_all_falls_back_to_batch_only() -> None:
    def make(feed: FeedMode) -> str:
        if feed == "all":
            raise CellError("too many tiles for the belt")
        return f"env({feed})"

    assert with_feed_fallback(make, "all") == ("env(batch)", FALLBACK_FEED)
    assert with_feed_fallback(make, "stream") == ("env(stream)", "stream")

    def never(feed: FeedMode) -> str:
        raise CellError(f"bad slots ({feed})")

    with pytest.raises(CellError, match="bad slots \\(stream\\)"):
        with_feed_fallback(never, "stream")
    with pytest.raises(CellError, match="bad slots \\(batch\\)"):
        with_feed_fallback(never, "all")


def test_feed_modes_have_one_home() -> None:
    assert FEED_MODES == FEEDS == get_args(SpecFeedMode) == ("all", "stream", "batch")
    with pytest.raises(CellError, match="allowed: 'all', 'stream', 'batch'"):
        TileConfig(feed="belt")  # type: ignore[arg-type]
    assert RunConfig(feed="batch").feed == "batch"
