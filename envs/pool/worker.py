"""The design pool's worker process (`envs.pool`).

What it makes of a generator state (`prepare`), its loop (`work`) and how it is stopped
(`stop`).
"""

from __future__ import annotations

import io
import pickle
import queue
import time
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

if TYPE_CHECKING:
    from envs.cell.cell import Cell
    from envs.design_source import ProceduralDesigns
    from envs.env_config import EnvConfig

State = Mapping[str, Any]
"""A bit generator's state (``np.random.Generator.bit_generator.state``)."""
STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS
"""The part of a cell's MuJoCo data a prepared entry carries (`dumps`)."""
STOP_WAIT_S = 5.0
"""Longest wait [s] for the worker to stop on its own at ``close`` before it is terminated."""


@dataclass(frozen=True)
class Prepared:
    """What the worker made of one generator state.

    Attributes:
        blob: (design, build seed, generator state after the draw, cell or None), `dumps`;
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


def state_key(state: State) -> str:
    """A generator state (``bit_generator.state``) as a hashable text."""
    return repr(state)


def _generator(state: State) -> np.random.Generator:
    """A generator of ``state``'s bit generator, at that state."""
    rng = np.random.Generator(getattr(np.random, state["bit_generator"])())
    rng.bit_generator.state = state
    return rng


def prepare(source: tuple[EnvConfig, ProceduralDesigns, bool], state: State) -> Prepared:
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
            blob: bytes | None = dumps((design, seed, after, cell), cell)
            error = ""
        except Exception as exc:  # noqa: BLE001 - any failure: the env draws in place
            blob, error = None, f"{type(exc).__name__}: {exc}"
    said = tuple((w.category, str(w.message)) for w in caught)
    return Prepared(blob, said, time.process_time() - cpu, error)


class _Pickler(pickle.Pickler):
    """Pickles a prepared entry with its cell's model and data left out (`dumps`)."""

    def __init__(self, file: io.BytesIO, model: Any, data: Any) -> None:
        super().__init__(file, protocol=pickle.HIGHEST_PROTOCOL)
        self._ids = {id(model): "model", id(data): "data"}

    def persistent_id(self, obj: Any) -> str | None:
        return self._ids.get(id(obj))


class _Unpickler(pickle.Unpickler):
    def __init__(self, file: io.BytesIO, model: Any, data: Any) -> None:
        super().__init__(file)
        self._objects = {"model": model, "data": data}

    def persistent_load(self, pid: Any) -> Any:
        return self._objects[pid]


def dumps(entry: tuple[Any, ...], cell: Cell | None) -> bytes:
    """Pickle ``entry`` (it holds ``cell``, or no cell: None).

    The cell's MuJoCo data goes as its physics state (`STATE`): at `loads` a new data of the
    model is set to it and forwarded, which costs a third of unpickling the data. Everything
    else of the cell is pickled as it is.
    """
    if cell is None:
        return pickle.dumps((None, None, entry), protocol=pickle.HIGHEST_PROTOCOL)
    model, data = cell.model, cell.data
    state = np.empty(mujoco.mj_stateSize(model, STATE))
    mujoco.mj_getState(model, data, state, STATE)
    buf = io.BytesIO()
    _Pickler(buf, model, data).dump(entry)
    model_blob = pickle.dumps(model, protocol=pickle.HIGHEST_PROTOCOL)
    return pickle.dumps((model_blob, state, buf.getvalue()), protocol=pickle.HIGHEST_PROTOCOL)


def loads(blob: bytes) -> Any:
    """The entry `dumps` pickled, its cell with a new data at the pickled physics state.

    The data's kinematics are forwarded (`mujoco.mj_forward`), as the cell's were when built:
    what its env reads before the episode's reset (camera and tool poses, tile poses) is the
    same; the reset then clears the data (`mujoco.mj_resetData`) as for any cell.
    """
    model_blob, state, rest = pickle.loads(blob)
    if model_blob is None:
        return rest
    model = pickle.loads(model_blob)
    data = mujoco.MjData(model)
    mujoco.mj_setState(model, data, state, STATE)
    mujoco.mj_forward(model, data)
    return _Unpickler(io.BytesIO(rest), model, data).load()


def work(requests: Any, results: Any) -> None:
    """The worker: prepare the states of the latest plan, in order, until told to stop."""
    source: Any = None
    digest = ""
    plan: list[tuple[str, State]] = []
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
        results.put(("ready", digest, key, prepare(source, state)))
        done.add(key)


def stop(process: Any, requests: Any, results: Any) -> None:
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


__all__ = [
    "STATE",
    "STOP_WAIT_S",
    "Prepared",
    "State",
    "dumps",
    "loads",
    "prepare",
    "state_key",
    "stop",
    "work",
]
