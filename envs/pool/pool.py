"""`DesignPool`: the env's side of the design pool (see `envs.pool`)."""

from __future__ import annotations

import copy
import hashlib
import multiprocessing as mp
import os
import pickle
import shutil
import tempfile
import time
import warnings
import weakref
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from gymnasium.utils import seeding

from envs.pool.config import DesignPoolConfig, load_pool_config
from envs.pool.worker import (
    Prepared,
    State,
    discard,
    loads,
    state_key,
    stop,
    take_over,
    work,
)
from envs.task import SEED_BOUND

if TYPE_CHECKING:
    from envs.cell.cell import Cell
    from envs.design_source import ProceduralDesigns
    from envs.env_config import EnvConfig
    from qshape.design import Design

MB = 2**20
"""Bytes per MB."""
MEMORY_FOLDER = "/dev/shm"
"""Where the pool's folder of handed-over entries is made when it exists (a file system in
memory); else in the system's temporary folder."""


@dataclass(frozen=True)
class Taken:
    """A prepared design taken at a reset (the generator already moved past its draw).

    Attributes:
        design: The drawn design.
        seed: The cell's build seed drawn after it.
        cell: Its cell, built in the worker (None with ``build_cells: false``).
    """

    design: Design
    seed: int
    cell: Cell | None = field(default=None)


class DesignPool:
    """Prepares procedural designs ahead in one worker process (see `envs.pool`).

    Args:
        config: The pool's settings.

    Attributes:
        hits: Resets that took a prepared design.
        misses: Resets that drew in place.
        dropped: Prepared entries thrown away (stale, larger than ``max_entry_mb``, or
            beyond ``ahead``).
        worker_cpu_s: CPU time the worker spent on the entries received [s].
    """

    def __init__(self, config: DesignPoolConfig) -> None:
        self.config = config
        ctx: Any = mp.get_context(config.start_method)
        worker_requests, self._requests = ctx.Pipe(duplex=False)
        self._results, worker_results = ctx.Pipe(duplex=False)
        here = MEMORY_FOLDER if os.path.isdir(MEMORY_FOLDER) else None
        self.folder = tempfile.mkdtemp(prefix="mosaic-design-pool-", dir=here)
        self._process: Any = ctx.Process(
            target=work,
            args=(worker_requests, worker_results, self.folder),
            name="mosaic-design-pool",
            daemon=True,
        )
        self._process.start()
        worker_requests.close()  # the worker's ends: its own copies live in its process
        worker_results.close()
        self._stop = weakref.finalize(
            self, _shut_down, self._process, self._requests, self._results, self.folder
        )
        self._digest = ""
        self._what: tuple[Any, ...] | None = None
        self._ready: OrderedDict[str, Prepared] = OrderedDict()
        self._plan: list[str] = []
        self._states: dict[str, State] = {}
        self._delivered: set[str] = set()
        self._started = ""
        self._seeds: OrderedDict[int, tuple[str, State]] = OrderedDict()
        self.hits = 0
        self.misses = 0
        self.dropped = 0
        self.worker_cpu_s = 0.0

    # ------------------------------------------------------------------ state
    @property
    def pid(self) -> int:
        """The worker's process id."""
        return int(self._process.pid)

    @property
    def alive(self) -> bool:
        """Whether the worker runs."""
        return bool(self._process.is_alive())

    def __len__(self) -> int:
        """Prepared entries held now (at most ``ahead``)."""
        return len(self._ready)

    @property
    def held_mb(self) -> float:
        """Memory of the prepared entries held now [MB] (their pickled size, in files)."""
        return sum(p.size for p in self._ready.values()) / MB

    # ------------------------------------------------------------------ use
    def source(self, config: EnvConfig, designs: ProceduralDesigns) -> str:
        """Make ``config`` and ``designs`` what the worker draws from; their digest.

        A digest other than the last one's drops every prepared entry (they were drawn or
        built from another configuration).
        """
        what = (config, designs.generator.config, designs.generator.rules, designs.tries)
        if self._what is not None and all(a is b for a, b in zip(what, self._what, strict=True)):
            return self._digest  # the very same (frozen) objects: nothing changed
        self._what = what
        digest = hashlib.sha256(pickle.dumps(what)).hexdigest()
        if digest != self._digest:
            bare = copy.copy(designs)
            bare.last = None
            payload = pickle.dumps((config, bare, self.config.build_cells))
            self._digest = digest
            self.dropped += len(self._ready)
            self._drop_all()
            self._plan, self._started, self._delivered = [], "", set()
            self._requests.send(("source", digest, payload))
        return digest

    def take(
        self, config: EnvConfig, designs: ProceduralDesigns, rng: np.random.Generator
    ) -> Taken | None:
        """The prepared design of ``rng``'s state, or None (the env then draws in place).

        On a hit ``rng`` is moved to the state its draw left it in and ``designs.last`` is
        set, as `ProceduralDesigns.draw` and the build seed's draw would have.
        """
        self.source(config, designs)
        key = state_key(rng.bit_generator.state)
        self._collect(0.0)
        if key not in self._ready and key in self._plan and key not in self._delivered:
            self._wait(key)
        prepared = self._ready.pop(key, None)
        blob = None if prepared is None else take_over(prepared)
        if prepared is None or blob is None:
            self.misses += 1
            return None
        design, seed, after, cell = loads(blob)
        for category, message in prepared.warnings:
            warnings.warn(message, category, stacklevel=4)
        rng.bit_generator.state = after
        designs.last = design
        self.hits += 1
        return Taken(design, seed, cell)

    def plan(self, rng: np.random.Generator, seed: int | None) -> None:
        """Ask for the states the next reset likely starts from (see `envs.pool`)."""
        if seed is not None:
            keyed = [self._seed_state(seed + k) for k in range(1, self.config.ahead + 1)]
        else:
            state = rng.bit_generator.state
            keyed = [(state_key(state), state)]
        plan = [k for k, _ in keyed]
        for k in [k for k in self._ready if k not in plan]:
            discard(self._ready.pop(k))
            self.dropped += 1
        if plan != self._plan:
            self._send_plan(keyed)

    def _seed_state(self, seed: int) -> tuple[str, State]:
        """(key, state) of ``np_random`` right after ``reset(seed=seed)`` (remembered)."""
        if seed not in self._seeds:
            state = seeding.np_random(seed)[0].bit_generator.state
            self._seeds[seed] = (state_key(state), state)
            while len(self._seeds) > 2 * self.config.ahead:
                self._seeds.popitem(last=False)
        return self._seeds[seed]

    def _wait(self, key: str) -> None:
        """Wait (up to ``wait_s``) for the planned entry ``key``, asked for first."""
        if self._started != key and self._plan[0] != key:
            keyed = [(k, self._states[k]) for k in (key, *(k for k in self._plan if k != key))]
            self._send_plan(keyed)
        deadline = time.monotonic() + self.config.wait_s
        while key in self._plan and key not in self._delivered and self.alive:
            left = deadline - time.monotonic()
            if left <= 0.0:
                return
            self._collect(left)

    def _send_plan(self, keyed: list[tuple[str, State]]) -> None:
        """Make ``keyed`` ((key, state), in order) the worker's plan."""
        self._plan = [k for k, _ in keyed]
        self._states = dict(keyed)
        self._delivered &= set(self._plan)  # as the worker forgets what left its plan
        self._requests.send(("plan", self._digest, keyed))

    def _collect(self, wait_s: float) -> None:
        """Receive what the worker sent (waiting up to ``wait_s`` for the first message)."""
        wait: float | None = wait_s
        while True:
            try:
                if not self._results.poll(wait):
                    return
                msg = self._results.recv()
            except (EOFError, OSError):
                return  # the worker is gone: the env draws in place from now on
            wait = 0.0
            if msg[0] == "started":
                self._started = msg[2] if msg[1] == self._digest else ""
                continue
            _, digest, key, prepared = msg
            self._started = ""
            if digest == self._digest:
                self._delivered.add(key)  # the worker will not make it again
            self.worker_cpu_s += prepared.cpu_s
            size = prepared.size / MB
            if digest != self._digest or key not in self._plan or size > self.config.max_entry_mb:
                discard(prepared)
                self.dropped += 1
                continue
            self._ready[key] = prepared
            while len(self._ready) > self.config.ahead:
                discard(self._ready.popitem(last=False)[1])
                self.dropped += 1

    def _drop_all(self) -> None:
        """Drop every prepared entry held (their files removed)."""
        for prepared in self._ready.values():
            discard(prepared)
        self._ready.clear()

    def close(self) -> None:
        """Stop the worker, drop every entry and remove the pool's folder (safe twice)."""
        self._drop_all()
        self._stop()


def _shut_down(process: Any, requests: Any, results: Any, folder: str) -> None:
    """Stop the worker (`stop`), then remove the folder of handed-over entries."""
    stop(process, requests, results)
    shutil.rmtree(folder, ignore_errors=True)


def draw_design(
    pool: DesignPool | None,
    config: EnvConfig,
    designs: ProceduralDesigns,
    rng: np.random.Generator,
) -> Taken:
    """The design of a procedural reset from ``rng``: taken from ``pool``, else drawn here.

    Drawn here: `ProceduralDesigns.draw`, then the cell's build seed (no cell: the env builds
    it). Either way ``rng`` ends in the same state.

    Raises:
        DesignSourceError: No design free of the excluded classes (drawn here).
    """
    taken = pool.take(config, designs, rng) if pool is not None else None
    if taken is not None:
        return taken
    design = designs.draw(rng)
    return Taken(design, int(rng.integers(SEED_BOUND)))


def design_pool(config: EnvConfig, designs: ProceduralDesigns | None) -> DesignPool | None:
    """The pool of ``config.design_pool`` for a procedural source, else None.

    None too in a daemonic process (which may not start one), with a warning.

    Raises:
        DesignPoolError: A bad pool configuration file.
    """
    if designs is None or config.design_pool is None:
        return None
    pool_config = load_pool_config(config.design_pool)
    if mp.current_process().daemon:
        warnings.warn(
            "design_pool: a daemonic process (e.g. an AsyncVectorEnv worker) may not start "
            "the pool's worker; this env draws its designs itself",
            RuntimeWarning,
            stacklevel=3,
        )
        return None
    return DesignPool(pool_config)


__all__ = ["MB", "MEMORY_FOLDER", "DesignPool", "Taken", "design_pool", "draw_design"]
