r"""Behaviour cloning from Minari demonstrations of the decision-level tasks.

Run::

    python -m apps.record_demos --task MosaicDecision6-v0 --expert --episodes 50 \\
        --dataset-id mosaic/decision6-expert-v0
    python -m apps.bc.decision --dataset-id mosaic/decision6-expert-v0 --out runs/bc [--seed 0]
    python -m apps.evaluate --task MosaicDecision6-v0 --policies runs/bc/bc.pt
    python -m apps.bc.decision --dataset-id mosaic/decision6-expert-v0 --config bc_pair \\
        --out runs/pair

``--arch pair`` (or ``arch: pair`` in the config, ``configs/bc_pair.yaml``) clones into the
pair scorer of `agents.pair.scorer` instead: one network with shared weights applied to every
(tile row, slot row) pair, one logit per (tile, slot, rotation), forbidden pairs masked from
the observation's own flags (`agents.pair.state_rows`).

A multilayer perceptron maps the state observation (``robot``, ``tiles``, ``slots``
concatenated) to one categorical over the flat ``(tile, slot, rotation)`` actions, trained
with cross-entropy on every recorded step (`BCConfig`, ``configs/bc.yaml``). The file
``bc.pt`` holds the weights, the spaces' sizes and the configuration; `BCPolicy` plays it
(a ``.pt`` path is a policy name of `apps.evaluate`).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from agents.learning.decision_bc import ARCHS, BC_CONFIG, load_bc_config, train_bc
from apps.cli import CommandParser, run_cli
from apps.record_demos import DEFAULT_ROOT, load


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line (see the module docstring)."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dataset-id", required=True)
    ap.add_argument("--root", type=Path, default=DEFAULT_ROOT)
    ap.add_argument("--out", type=Path, default=Path("runs/bc"))
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--config", default=BC_CONFIG, help="name in configs/ or a YAML path")
    ap.add_argument("--arch", choices=ARCHS, default=None, help="override the config's arch")
    args = ap.parse_args(argv)
    import torch  # noqa: PLC0415 - heavy import

    torch.set_num_threads(1)
    overrides = {"arch": args.arch} if args.arch else {}
    summary = train_bc(
        load(args.dataset_id, args.root),
        args.out,
        args.seed,
        load_bc_config(args.config, **overrides),
    )
    print(json.dumps(summary, indent=2))
    return summary


__all__ = ["main"]

if __name__ == "__main__":
    run_cli(main)
