"""Mutation testing with mutmut 3: run it, report it against the targets, sample it in CI.

The modules, the tests and mutmut's settings are in ``pyproject.toml`` (``[tool.mutmut]``: the
one list of mutated modules is ``only_mutate``); the groups, their targets and the CI sample's
tests in ``[tool.mosaic-mutation]``; the equivalent mutants, each with its reason, in
``scripts/mutation_equivalent.yaml``. Page: ``docs/mutation_testing.md``.

Usage, from the repository root:

    python scripts/mutation.py run [--group scoring|rest] [--workers 2] [--resume]   # + report
    python scripts/mutation.py report [--json out/mutation.json]
    python scripts/mutation.py sample [--group scoring|rest] [--mutants 24] [--seed 0]

``run`` runs every non-equivalent mutant of both groups (or of ``--group``) afresh;
``--resume`` skips those with a result. ``report`` prints killed / non-equivalent per module
and group against its target (exit 1 below a target) and the survivors. ``sample`` draws
mutants of a group with a fixed seed and runs them in a throw-away copy of the tree: the
scoring group (default, CI) against the scoring contract tests only, exit 1 when one survives
that is not a reviewed equivalent; the rest against the whole selection, its killed share per
module with a 95 % interval, exit 1 below the group's target.
"""

from __future__ import annotations

import argparse
import fnmatch
import json
import math
import os
import random
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib
from collections import Counter, defaultdict
from pathlib import Path
from typing import Any

import yaml

ROOT = Path(__file__).resolve().parents[1]
EQUIVALENT = ROOT / "scripts" / "mutation_equivalent.yaml"
MUTMUT = Path(sys.executable).with_name("mutmut")
KILLED = {"killed", "timeout", "caught by type check", "segfault"}
"""Statuses that count as caught (a mutant that hangs or crashes the tests is noticed)."""
COPY_IGNORE = shutil.ignore_patterns(
    ".git", ".venv", "mutants", "out", "runs", "__pycache__", "*.pyc", ".*_cache", "docs"
)
BOOT = """
import dataclasses, json, sys
from mutmut import configuration
cfg = configuration.config()
configuration._config = dataclasses.replace(cfg, **json.loads(sys.argv[1]))
from mutmut.__main__ import cli
cli(["run", "--max-children", sys.argv[2], *sys.argv[3:]])
"""
"""Runs mutmut with some of pyproject's [tool.mutmut] settings replaced (the CI sample)."""


class MutationError(Exception):
    """A setting or a file of the mutation run is missing or wrong."""


def settings() -> tuple[dict[str, Any], dict[str, Any]]:
    """([tool.mutmut], [tool.mosaic-mutation]) of pyproject.toml, checked against the tree."""
    tool = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]
    mm, ours = tool["mutmut"], tool["mosaic-mutation"]
    for pattern in mm["only_mutate"]:
        if not any(fnmatch.fnmatch(str(p.relative_to(ROOT)), pattern) for p in _sources(mm)):
            raise MutationError(f"[tool.mutmut] only_mutate {pattern!r} matches no file")
    for pattern in ours["scoring"]:
        if pattern not in mm["only_mutate"]:
            raise MutationError(f"scoring module {pattern!r} is not in [tool.mutmut] only_mutate")
    return mm, ours


def _sources(mm: dict[str, Any]) -> list[Path]:
    return [p for d in mm["source_paths"] for p in (ROOT / d).rglob("*.py")]


def module_of(pattern: str) -> str:
    """A file glob of only_mutate as a mutant-name glob: envs/task.py -> envs.task.*."""
    return pattern.removesuffix(".py").removesuffix("*").rstrip("/").replace("/", ".") + ".*"


def group_of(name: str, ours: dict[str, Any]) -> str:
    """``scoring`` or ``rest`` for a mutant name."""
    scoring = any(fnmatch.fnmatch(name, module_of(p)) for p in ours["scoring"])
    return "scoring" if scoring else "rest"


def group_files(mm: dict[str, Any], ours: dict[str, Any], group: str) -> list[str]:
    """The only_mutate file globs of group ``scoring`` or ``rest``."""
    return [p for p in mm["only_mutate"] if (p in ours["scoring"]) == (group == "scoring")]


def equivalent() -> dict[str, str]:
    """Reviewed equivalent mutants: name -> reason."""
    data = yaml.safe_load(EQUIVALENT.read_text(encoding="utf-8")) or {}
    if not isinstance(data, dict) or not all(isinstance(v, str) and v for v in data.values()):
        raise MutationError(f"{EQUIVALENT.name}: a mapping of mutant name -> reason expected")
    return data


def results(root: Path = ROOT) -> dict[str, str]:
    """Mutant name -> mutmut status, from the ``.meta`` files of ``root/mutants``."""
    from mutmut.stats import status_by_exit_code  # noqa: PLC0415 - only where mutmut runs

    out: dict[str, str] = {}
    for meta in sorted((root / "mutants").rglob("*.py.meta")):
        data = json.loads(meta.read_text(encoding="utf-8"))
        for name, code in data.get("exit_code_by_key", {}).items():
            out[name] = status_by_exit_code[code]
    return out


def diff_line(name: str) -> str:
    """The changed line of a mutant (``-old`` / ``+new``), from mutants/ of the checkout."""
    from mutmut.mutation.diff_apply import get_diff_for_mutant  # noqa: PLC0415

    cwd = os.getcwd()
    os.chdir(ROOT)
    try:
        diff = get_diff_for_mutant(name)
    except Exception as exc:  # noqa: BLE001 - a report line, not a failure
        return f"(no diff: {exc})"
    finally:
        os.chdir(cwd)
    lines = [ln for ln in diff.splitlines()[2:] if ln[:1] in "+-"]
    return " / ".join(ln.strip() for ln in lines)


def report(args: argparse.Namespace) -> int:
    """Print per-module and per-group figures against the targets; list the survivors."""
    _, ours = settings()
    status = results()
    if not status:
        print("no mutation results: run `python scripts/mutation.py run` first")
        return 1
    eq = equivalent()
    per: dict[str, Counter[str]] = defaultdict(Counter)
    survivors = []
    for name, st in status.items():
        module = name.split(".x")[0]
        if name in eq:  # reviewed: counted whether or not it was run
            per[module]["mutants"] += 1
            per[module]["equivalent"] += 1
            continue
        if st == "not checked":
            per[module]["not run"] += 1
            continue
        per[module]["mutants"] += 1
        if st in KILLED:
            per[module]["killed"] += 1
        elif st == "survived":
            per[module]["survived"] += 1
            survivors.append(name)
        else:
            per[module][st] += 1
    print(
        f"{'module':34} {'mutants':>7} {'equiv':>5} {'killed':>6} {'surv':>5} {'other':>5}  score"
    )
    groups: dict[str, Counter[str]] = defaultdict(Counter)
    for module in sorted(per):
        c = per[module]
        other = c["mutants"] - c["equivalent"] - c["killed"] - c["survived"]
        live = c["mutants"] - c["equivalent"]
        score = f"{100 * c['killed'] / live:5.1f} %" if live else "  -"
        note = f"  ({c['not run']} not run)" if c["not run"] else ""
        print(
            f"{module:34} {c['mutants']:7} {c['equivalent']:5} {c['killed']:6} "
            f"{c['survived']:5} {other:5}  {score}{note}"
        )
        groups[group_of(module + ".x", ours)].update(c)
    failed = 0
    out: dict[str, Any] = {"modules": {m: dict(c) for m, c in per.items()}, "groups": {}}
    for group, c in sorted(groups.items()):
        live = c["mutants"] - c["equivalent"]
        if not live:
            continue
        share = c["killed"] / live
        target = float(ours["targets"][group])
        ok = share >= target
        failed += not ok
        print(
            f"{group}: {c['killed']}/{live} non-equivalent mutants killed = {100 * share:.1f} % "
            f"(target {100 * target:.0f} %: {'met' if ok else 'MISSED'})"
            + (f"; {c['not run']} not run" if c["not run"] else "")
        )
        out["groups"][group] = {"killed": c["killed"], "non_equivalent": live, "score": share}
    print(f"\n{len(survivors)} survivors (not reviewed as equivalent):")
    for name in sorted(survivors):
        print(f"  {name}: {diff_line(name) if args.diffs else ''}")
    out["survivors"] = sorted(survivors)
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(out, indent=2) + "\n", encoding="utf-8")
    return 1 if failed else 0


def run(args: argparse.Namespace) -> int:
    """Mutmut run of every non-equivalent mutant (both groups, or one), timed, then the report.

    The mutants are named to mutmut one by one, so each is run afresh and the reviewed
    equivalents (``scripts/mutation_equivalent.yaml``) are not run at all: none of their tests
    can fail, so each would cost every test that calls its function. ``--resume`` keeps the
    mutants that already have a result (a run stopped half-way goes on).
    """
    mm, ours = settings()
    eq = equivalent()
    groups = [args.group] if args.group else ["scoring", "rest"]
    patterns = [p for g in groups for p in group_files(mm, ours, g)]
    made = mutant_names(ROOT, patterns)
    names = [n for n in made if n not in eq]
    skipped = len(made) - len(names)
    if args.resume:
        done = {n for n, st in results().items() if st != "not checked"}
        names = [n for n in names if n not in done]
    print(
        f"run: {len(names)} mutants of {' and '.join(groups)} "
        f"({skipped} reviewed equivalents not run)"
    )
    sys.stdout.flush()
    t0 = time.monotonic()
    code = 0
    if names:
        code = subprocess.call(
            [str(MUTMUT), "run", "--max-children", str(args.workers), *names],
            cwd=ROOT,
            env=_env(),
        )
    print(f"mutmut run: {time.monotonic() - t0:.0f} s wall, {args.workers} workers")
    if code:
        return code
    return report(args)


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env.setdefault("MUJOCO_GL", "egl")
    env.setdefault("PYOPENGL_PLATFORM", "egl")
    for var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        env.setdefault(var, "1")  # one core per worker
    return env


def mutant_names(root: Path, patterns: list[str]) -> list[str]:
    """Every mutant mutmut makes of the files matching ``patterns`` (its own generator)."""
    from mutmut.mutation.file_mutation import mutate_file_contents  # noqa: PLC0415
    from mutmut.utils.format_utils import get_mutant_name  # noqa: PLC0415

    cwd = os.getcwd()
    os.chdir(root)  # mutmut reads its settings (pragmas, patterns) from the working directory
    try:
        names = []
        for pattern in patterns:
            for path in sorted(Path().glob(pattern)):
                made = mutate_file_contents(str(path), path.read_text(encoding="utf-8"))
                names += [get_mutant_name(path, n) for n in made.mutant_names]
        return names
    finally:
        os.chdir(cwd)


def sample(args: argparse.Namespace) -> int:
    """Run a seeded sample of one group's mutants in a throw-away copy of the tree.

    ``scoring`` (CI): against the scoring contract tests only (``sample_tests``); exit 1 when
    one survives or no test reaches it. ``rest``: against the whole test selection of
    ``[tool.mutmut]``; prints the killed share per module and exit 1 below the group's target
    (an estimate of the full group's figure, with its 95 % interval).
    """
    mm, ours = settings()
    eq = equivalent()
    patterns = group_files(mm, ours, args.group)
    overrides: dict[str, Any] = {"only_mutate": patterns}
    if args.group == "scoring":
        overrides["pytest_add_cli_args_test_selection"] = ours["sample_tests"]
    t0 = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="mutation-sample-") as tmp:
        work = Path(tmp) / "tree"
        shutil.copytree(ROOT, work, ignore=COPY_IGNORE)
        pool = [n for n in mutant_names(work, patterns) if n not in eq]
        chosen = sorted(random.Random(args.seed).sample(pool, min(args.mutants, len(pool))))
        print(f"sample: {len(chosen)} of {len(pool)} {args.group} mutants (seed {args.seed})")
        sys.stdout.flush()
        code = subprocess.call(
            [sys.executable, "-c", BOOT, json.dumps(overrides), str(args.workers), *chosen],
            cwd=work,
            env=_env(),
            stdout=subprocess.DEVNULL if args.quiet else None,
        )
        status = results(work)
    missed = [n for n in chosen if status.get(n) == "survived"]
    unknown = [n for n in chosen if status.get(n) in (None, "not checked", "no tests")]
    killed = [n for n in chosen if status.get(n) in KILLED]
    wall = time.monotonic() - t0
    print(
        f"sample: {len(killed)} killed, {len(missed)} survived, {len(unknown)} not tested, "
        f"in {wall:.0f} s (mutmut exit {code})"
    )
    if args.group == "rest":
        whole = len(chosen) == len(pool)
        return _sample_figure(
            chosen, status, float(ours["targets"]["rest"]), missed + unknown, whole
        )
    for n in missed:
        print(
            f"  SURVIVED {n}: write a test that kills it, or review it as equivalent "
            f"({EQUIVALENT.relative_to(ROOT)})"
        )
    for n in unknown:
        print(f"  NOT TESTED {n}: no test of the sample's selection calls it")
    return 1 if missed or unknown or code else 0


def _sample_figure(
    chosen: list[str], status: dict[str, str], target: float, lost: list[str], whole: bool
) -> int:
    """Per-module and overall killed share of a sample, a 95 % interval; exit 1 below target.

    A mutant the run did not reach (stopped early) is left out; one no test calls counts as
    survived.
    """
    per: dict[str, Counter[str]] = defaultdict(Counter)
    for n in chosen:
        st = status.get(n, "not checked")
        key = "not run" if st == "not checked" else "killed" if st in KILLED else "survived"
        per[n.split(".x")[0]][key] += 1
    total: Counter[str] = Counter()
    print(f"{'module':34} {'killed':>6} {'surv':>5} {'not run':>7}  score")
    for module in sorted(per):
        c = per[module]
        total.update(c)
        live = c["killed"] + c["survived"]
        score = f"{100 * c['killed'] / live:5.1f} %" if live else "  -"
        print(f"{module:34} {c['killed']:6} {c['survived']:5} {c['not run']:7}  {score}")
    live = total["killed"] + total["survived"]
    if not live:
        print("rest sample: no mutant ran")
        return 1
    p = total["killed"] / live
    half = 1.96 * math.sqrt(p * (1.0 - p) / live)
    ok = p >= target
    spread = (
        "the whole group"
        if whole
        else f"95 % interval {100 * max(0.0, p - half):.1f}-{100 * min(1.0, p + half):.1f} %"
    )
    print(
        f"rest sample: {total['killed']}/{live} killed = {100 * p:.1f} % "
        f"({spread}; target {100 * target:.0f} %: {'met' if ok else 'MISSED'})"
    )
    for n in sorted(lost):
        if status.get(n, "not checked") != "not checked":
            print(f"  SURVIVED {n}")
    return 0 if ok else 1


def main(argv: list[str] | None = None) -> int:
    """Parse the command line and run one command."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="mutmut run, then the report")
    r.add_argument("--group", choices=("scoring", "rest"))
    r.add_argument("--workers", type=int, default=2)
    r.add_argument("--resume", action="store_true", help="skip mutants that have a result")
    for p in (r, sub.add_parser("report", help="figures against the targets, survivors")):
        p.add_argument("--json", type=Path, default=ROOT / "out" / "mutation.json")
        p.add_argument("--no-diffs", dest="diffs", action="store_false")
    s = sub.add_parser("sample", help="a seeded sample of one group's mutants")
    s.add_argument("--group", choices=("scoring", "rest"), default="scoring")
    s.add_argument("--mutants", type=int, default=24)
    s.add_argument("--seed", type=int, default=0)
    s.add_argument("--workers", type=int, default=2)
    s.add_argument("--quiet", action="store_true", help="hide mutmut's progress output")
    args = ap.parse_args(argv)
    try:
        return {"run": run, "report": report, "sample": sample}[args.command](args)
    except MutationError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
