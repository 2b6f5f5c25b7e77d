"""Procedural designs (and their cells) prepared ahead in a worker process: `DesignPool`.

A ``design_source: procedural`` env draws a design and builds its cell at every reset, from
its ``np_random`` (`envs.design_source`). What is drawn is a function of that generator's state
at the reset alone, so another process can draw it ahead if it knows the state. With
``design_pool`` set (``gym.make(..., design_pool="design_pool")``, `DesignPoolConfig`), the env
starts one worker process that, while episodes run, draws the designs of the states the next
reset is likely to start from and builds their cells (compiled MuJoCo model included):

- after ``reset(seed=s)``: the states of seeds ``s + 1`` ... ``s + ahead`` (evaluation and
  benchmark loops walk the seeds in order);
- after ``reset()`` without a seed: the generator's state now, which is the next reset's
  when the episode draws nothing from ``np_random`` (no action noise; Gymnasium's vector
  envs reset so).

At a reset the env looks its state up: a prepared design is taken (the generator is moved to
the state the draw left it in, exactly as if drawn here), one the worker is preparing is
waited for, anything else is drawn in the env's process as without a pool. The same seed
therefore gives the same episode with or without the pool, bit for bit (tested against the
recorded rollout fingerprints).

Every entry is keyed by the generator's full state and a digest of everything the draw and
the build read (the env configuration, the cell's included, and the design generator's
parameters and rules): a changed design or cell configuration never takes a stale design or
model. The pool holds at most ``ahead`` prepared entries, each at most ``max_entry_mb``
(larger ones are dropped): at most ``ahead x max_entry_mb`` MB. ``env.close()`` stops the
worker (it is also stopped when the pool is garbage-collected and at interpreter exit). In a
daemonic process (the workers of Gymnasium's ``AsyncVectorEnv``), which may not start
processes, the pool is not started (a warning says so) and designs are drawn in place.
"""

from __future__ import annotations

import copy
import gc
import hashlib
import multiprocessing as mp
import pickle
import queue
import time
import warnings
import weakref
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, get_args

import numpy as np
from gymnasium.utils import seeding

from configs import ConfigError, check_field_types, load_config
from configs.checks import check_fields, checked
from envs.errors import EnvError

if TYPE_CHECKING:
    from envs.cell.cell import Cell
    from envs.design_source import ProceduralDesigns
    from envs.env_config import EnvConfig
    from qshape.design import Design

StartMethod = Literal["spawn", "forkserver"]
START_METHODS: tuple[str, ...] = get_args(StartMethod)
"""Allowed ``start_method`` values (never ``fork``: a forked worker can hang in EGL)."""
MB = 2**20
"""Bytes per MB."""
STOP_WAIT_S = 5.0
"""Longest wait [s] for the worker to stop on its own at ``close`` before it is terminated."""


class DesignPoolError(EnvError, ValueError):
    """A bad design pool configuration (names the key and what is allowed)."""


@dataclass(frozen=True)
class DesignPoolConfig:
    """Settings of the design pool (``configs/design_pool.yaml``).

    Attributes:
        ahead: Designs prepared ahead at most, ready or in work [count].
        build_cells: Also build each design's cell (its compiled MuJoCo model, tiles, layout)
            in the worker; False: only the design is drawn there.
        max_entry_mb: A prepared entry (design, cell) larger than this is dropped [MB]. The
            pool's memory bound is ``ahead x max_entry_mb`` (`max_mb`).
        wait_s: Longest wait at a reset for the design the worker is preparing [s]; then the
            env draws it itself.
        start_method: How the worker process starts, one of `START_METHODS`.
    """

    ahead: int = checked(4, ge=1, integer=True)
    build_cells: bool = True
    max_entry_mb: float = checked(16.0, gt=0)
    wait_s: float = checked(30.0, gt=0)
    start_method: StartMethod = checked("spawn", choices=START_METHODS)

    def __post_init__(self) -> None:
        try:
            check_field_types(self)
        except ConfigError as exc:
            raise DesignPoolError(str(exc)) from exc
        check_fields(self, DesignPoolError)

    @property
    def max_mb(self) -> float:
        """Most memory the prepared entries hold together [MB]."""
        return self.ahead * self.max_entry_mb


def load_pool_config(name_or_path: str | Path, **overrides: Any) -> DesignPoolConfig:
    """The pool configuration of a bundled name (``"design_pool"``) or a path, with overrides.

    Raises:
        DesignPoolError: Missing file, unknown key or a value out of range (named).
    """
    try:
        return load_config(DesignPoolConfig, name_or_path, **overrides)
    except ConfigError as exc:
        raise DesignPoolError(f"design_pool {str(name_or_path)!r}: {exc}") from exc


@dataclass(frozen=True)
class Prepared:
    """What the worker made of one generator state.

    Attributes:
        blob: Pickled (design, build seed, generator state after the draw, cell or None);
            None when the draw failed.
        warnings: (category, message) of each warning the draw and build gave.
        cpu_s: CPU time the worker spent on it [s].
        error: Why the draw failed ("" when it did not); the env then draws in place (and
            raises the same error).
    """

    blob: bytes | None
    warnings: tuple[tuple[type[Warning], str], ...] = ()
    cpu_s: float = 0.0
    error: str = ""


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


def state_key(state: dict[str, Any]) -> str:
    """A generator state (``bit_generator.state``) as a hashable text."""
    return repr(state)


def _generator(state: dict[str, Any]) -> np.random.Generator:
    """A generator of ``state``'s bit generator, at that state."""
    rng = np.random.Generator(getattr(np.random, state["bit_generator"])())
    rng.bit_generator.state = state
    return rng


def _prepare(source: tuple[EnvConfig, ProceduralDesigns, bool], state: dict[str, Any]) -> Prepared:
    """Draw the design of ``state`` (and build its cell) as the env's reset would."""
    from envs.env_parts import build_design_cell  # noqa: PLC0415 - the worker's imports
    from envs.task import SEED_BOUND  # noqa: PLC0415

    config, designs, build = source
    cpu = time.process_time()
    rng = _generator(state)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            design = designs.draw(rng)
            seed = int(rng.integers(SEED_BOUND))
            after = rng.bit_generator.state
            for slot in design.slots:
                slot.figure()  # made here, pickled with the design (the task's slots read them)
            cell = build_design_cell(config, design, seed)[1] if build else None
            blob: bytes | None = pickle.dumps(
                (design, seed, after, cell), protocol=pickle.HIGHEST_PROTOCOL
            )
            error = ""
        except Exception as exc:  # noqa: BLE001 - any failure: the env draws in place
            blob, error = None, f"{type(exc).__name__}: {exc}"
    said = tuple((w.category, str(w.message)) for w in caught)
    return Prepared(blob, said, time.process_time() - cpu, error)


def _loads(blob: bytes) -> Any:
    """Unpickle ``blob`` with the cyclic garbage collector paused.

    A cell is thousands of small objects: unpickled in a process that holds many more, the
    collector would otherwise walk them all several times over (three times the unpickling).
    """
    paused = gc.isenabled()
    gc.disable()
    try:
        return pickle.loads(blob)
    finally:
        if paused:
            gc.enable()


def _work(requests: Any, results: Any) -> None:
    """The worker: prepare the states of the latest plan, in order, until told to stop."""
    source: Any = None
    digest = ""
    plan: list[tuple[str, dict[str, Any]]] = []
    done: set[str] = set()
    while True:
        todo = [(k, s) for k, s in plan if k not in done]
        try:
            msg = requests.get(block=not todo)
        except queue.Empty:
            msg = None
        if msg is not None:  # take every message before working on the newest plan
            if msg[0] == "stop":
                results.cancel_join_thread()
                return
            if msg[0] == "source":
                digest, source, plan, done = msg[1], pickle.loads(msg[2]), [], set()
            elif msg[0] == "plan" and msg[1] == digest:
                plan = msg[2]
                done &= {k for k, _ in plan}
            continue
        key, state = todo[0]
        results.put(("started", digest, key))
        results.put(("ready", digest, key, _prepare(source, state)))
        done.add(key)


def _stop(process: Any, requests: Any, results: Any) -> None:
    """Stop the worker: ask, wait `STOP_WAIT_S`, then terminate; never block at exit."""
    if process.is_alive():
        try:
            requests.put(("stop",))
        except (OSError, ValueError):
            pass
        process.join(STOP_WAIT_S)
        if process.is_alive():
            process.terminate()
            process.join(STOP_WAIT_S)
    for q in (requests, results):
        q.cancel_join_thread()
        q.close()


class DesignPool:
    """Prepares procedural designs ahead in one worker process (see the module docstring).

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
        ctx = mp.get_context(config.start_method)
        self._requests: Any = ctx.Queue()
        self._results: Any = ctx.Queue()
        self._process: Any = ctx.Process(
            target=_work,
            args=(self._requests, self._results),
            name="mosaic-design-pool",
            daemon=True,
        )
        self._process.start()
        self._stop = weakref.finalize(self, _stop, self._process, self._requests, self._results)
        self._digest = ""
        self._what: tuple[Any, ...] | None = None
        self._ready: OrderedDict[str, Prepared] = OrderedDict()
        self._plan: list[str] = []
        self._states: dict[str, dict[str, Any]] = {}
        self._delivered: set[str] = set()
        self._started = ""
        self._seeds: OrderedDict[int, tuple[str, dict[str, Any]]] = OrderedDict()
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
        """Memory of the prepared entries held now [MB] (their pickled size)."""
        return sum(len(p.blob or b"") for p in self._ready.values()) / MB

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
            self._ready.clear()
            self._plan, self._started, self._delivered = [], "", set()
            self._requests.put(("source", digest, payload))
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
        if prepared is None or prepared.blob is None:
            self.misses += 1
            return None
        design, seed, after, cell = _loads(prepared.blob)
        for category, message in prepared.warnings:
            warnings.warn(message, category, stacklevel=4)
        rng.bit_generator.state = after
        designs.last = design
        self.hits += 1
        return Taken(design, seed, cell)

    def plan(self, rng: np.random.Generator, seed: int | None) -> None:
        """Ask for the states the next reset likely starts from (see the module docstring)."""
        if seed is not None:
            keyed = [self._seed_state(seed + k) for k in range(1, self.config.ahead + 1)]
        else:
            state = rng.bit_generator.state
            keyed = [(state_key(state), state)]
        plan = [k for k, _ in keyed]
        for k in [k for k in self._ready if k not in plan]:
            del self._ready[k]
            self.dropped += 1
        if plan != self._plan:
            self._send_plan(keyed)

    def _seed_state(self, seed: int) -> tuple[str, dict[str, Any]]:
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

    def _send_plan(self, keyed: list[tuple[str, dict[str, Any]]]) -> None:
        """Make ``keyed`` ((key, state), in order) the worker's plan."""
        self._plan = [k for k, _ in keyed]
        self._states = dict(keyed)
        self._delivered &= set(self._plan)  # as the worker forgets what left its plan
        self._requests.put(("plan", self._digest, keyed))

    def _collect(self, wait_s: float) -> None:
        """Receive what the worker sent (waiting up to ``wait_s`` for the first message)."""
        block = wait_s > 0.0
        while True:
            try:
                msg = self._results.get(block=block, timeout=wait_s if block else None)
            except queue.Empty:
                return
            block = False
            if msg[0] == "started":
                self._started = msg[2] if msg[1] == self._digest else ""
                continue
            _, digest, key, prepared = msg
            self._started = ""
            if digest == self._digest:
                self._delivered.add(key)  # the worker will not make it again
            self.worker_cpu_s += prepared.cpu_s
            size = len(prepared.blob or b"") / MB
            if digest != self._digest or key not in self._plan or size > self.config.max_entry_mb:
                self.dropped += 1
                continue
            self._ready[key] = prepared
            while len(self._ready) > self.config.ahead:
                self._ready.popitem(last=False)
                self.dropped += 1

    def close(self) -> None:
        """Stop the worker and drop every entry (safe to call twice)."""
        self._ready.clear()
        self._stop()


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


__all__ = [
    "START_METHODS",
    "DesignPool",
    "DesignPoolConfig",
    "DesignPoolError",
    "Prepared",
    "Taken",
    "design_pool",
    "load_pool_config",
    "state_key",
]
