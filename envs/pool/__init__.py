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

from envs.pool.config import START_METHODS, DesignPoolConfig, DesignPoolError, load_pool_config
from envs.pool.pool import DesignPool, Taken, design_pool, draw_design
from envs.pool.worker import Prepared, state_key

__all__ = [
    "START_METHODS",
    "DesignPool",
    "DesignPoolConfig",
    "DesignPoolError",
    "Prepared",
    "Taken",
    "design_pool",
    "draw_design",
    "load_pool_config",
    "state_key",
]
