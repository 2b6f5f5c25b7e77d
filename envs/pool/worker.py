"""The design pool's worker process (`envs.pool`).

What it makes of a generator state (`prepare`), its loop (`work`) and how it is stopped
(`stop`).
"""

from __future__ import annotations

import dataclasses
import io
import os
import pickle
import time
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from multiprocessing.connection import Connection
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
            None when the draw failed, and once handed over in a file (`hand_over`).
        warnings: (category, message) of each warning the draw and build gave.
        cpu_s: CPU time the worker spent on it [s].
        error: Why the draw failed ("" when it did not); the env then draws in place (and
            raises the same error).
        path: The file holding the blob once handed over ("" before, or without a blob).
        size: The blob's size [bytes].
    """

    blob: bytes | None
    warnings: tuple[tuple[type[Warning], str], ...] = ()
    cpu_s: float = 0.0
    error: str = ""
    path: str = ""
    size: int = 0


def hand_over(prepared: Prepared, path: str) -> Prepared:
    """``prepared`` with its blob written to the file ``path`` (nothing without a blob).

    A file in memory (the pool's folder is on ``/dev/shm`` where there is one) is read at
    once by the env at its reset: a megabyte through a pipe costs both processes many
    small reads and writes and their wake-ups.

    Raises:
        OSError: The file could not be written (a partly written one is removed).
    """
    if prepared.blob is None:
        return prepared
    try:
        with open(path, "wb") as f:
            f.write(prepared.blob)
    except OSError:  # e.g. a full /dev/shm: no partly written file stays behind
        discard(dataclasses.replace(prepared, path=path))
        raise
    return dataclasses.replace(prepared, blob=None, path=path, size=len(prepared.blob))


def take_over(prepared: Prepared) -> bytes | None:
    """The blob of a handed-over entry (its file removed); None without a blob."""
    if not prepared.path:
        return prepared.blob
    try:
        with open(prepared.path, "rb") as f:
            return f.read()
    finally:
        discard(prepared)


def discard(prepared: Prepared) -> None:
    """Remove a handed-over entry's file (if still there)."""
    if prepared.path:
        try:
            os.remove(prepared.path)
        except FileNotFoundError:
            pass


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


def work(requests: Connection, results: Connection, folder: str) -> None:
    """The worker: prepare the states of the latest plan, in order, until told to stop.

    Messages come and go through pipes (sent in the calling thread: no feeder thread and its
    wake-ups, as a queue has); each prepared blob is handed over as a file in ``folder``
    (`hand_over`). The worker ends when told to stop or when the env's end of the pipe is
    gone.
    """
    source: Any = None
    count = 0
    digest = ""
    plan: list[tuple[str, State]] = []
    done: set[str] = set()
    while True:
        todo = [(k, s) for k, s in plan if k not in done]
        try:
            msg = requests.recv() if not todo or requests.poll() else None
        except EOFError:
            return  # the env's end is closed
        if msg is not None:  # take every message before working on the newest plan
            if msg[0] == "stop":
                return
            if msg[0] == "source":
                digest, source, plan, done = msg[1], pickle.loads(msg[2]), [], set()
            elif msg[0] == "plan" and msg[1] == digest:
                plan = msg[2]
                done &= {k for k, _ in plan}
            continue
        key, state = todo[0]
        count += 1
        try:
            results.send(("started", digest, key))
        except OSError:
            return  # the env's end is closed: nobody to prepare for
        prepared = prepare(source, state)
        try:
            prepared = hand_over(prepared, os.path.join(folder, f"{count}.entry"))
        except OSError as exc:  # e.g. a full /dev/shm: this entry is drawn in place
            prepared = Prepared(None, prepared.warnings, prepared.cpu_s, f"hand-over: {exc}")
        try:
            results.send(("ready", digest, key, prepared))
        except OSError:
            return
        done.add(key)


def stop(process: Any, requests: Connection, results: Connection) -> None:
    """Stop the worker: ask, wait `STOP_WAIT_S`, then terminate; never block at exit."""
    if process.is_alive():
        try:
            requests.send(("stop",))
        except (OSError, ValueError):
            pass
        process.join(STOP_WAIT_S)
        if process.is_alive():
            process.terminate()
            process.join(STOP_WAIT_S)
    requests.close()
    results.close()


__all__ = [
    "STATE",
    "STOP_WAIT_S",
    "Prepared",
    "State",
    "discard",
    "dumps",
    "hand_over",
    "loads",
    "prepare",
    "state_key",
    "stop",
    "take_over",
    "work",
]
