"""Mutation testing of qshape: do its tests notice a one-line change to the source?

Each mutant is a copy of the project with one line of a qshape module changed (a comparison
flipped, a band edge shifted, a sign or an arithmetic operator changed, a boolean negated).
The qshape tests run on the copy; a failing run means the mutant was *caught*. Mutants are drawn
with a fixed seed from every candidate line, so a run is repeatable.

    python -m benchmarks.mutation --mutants 40   # caught/total; out/bench_mutation.json

A run takes about (mutants x one qshape test run); missed mutants are listed with file and line
so that a test can be written for each.
"""

from __future__ import annotations

import json
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from apps.cli import CommandParser, run_cli
from configs.files import write_text

ROOT = Path(__file__).resolve().parents[1]
MODULES = [
    "qshape/geometry.py",
    "qshape/theory/figure.py",
    "qshape/theory/description.py",
    "qshape/theory/labels.py",
    "qshape/theory/keys.py",
    "qshape/theory/evaluator.py",
    "qshape/theory/matching.py",
    "qshape/theory/text_parser.py",
    "qshape/theory/tolerances.py",
    "qshape/limits.py",
    "qshape/design/paths.py",
    "qshape/design/slot.py",
    "qshape/design/checks.py",
    "qshape/design/shapes.py",
]
TESTS = ["tests/test_qshape_*.py", "tests/test_design.py"]
OPERATORS: list[tuple[str, str, str]] = [
    ("flip <=", r"(?<![<>=!])<=(?!=)", ">"),
    ("flip >=", r"(?<![<>=!])>=(?!=)", "<"),
    ("strict <", r"(?<![<>=!-])<(?![<=])", "<="),
    ("strict >", r"(?<![<>=!-])>(?![>=])", ">="),
    ("== to !=", r"==", "!="),
    ("!= to ==", r"!=", "=="),
    ("+ to -", r"(?<=\w|\)) \+ (?=[\w(])", " - "),
    ("- to +", r"(?<=\w|\)) - (?=[\w(])", " + "),
    ("* to /", r"(?<=\w|\)) \* (?=[\w(])", " / "),
    ("and to or", r"\band\b", "or"),
    ("not removed", r"\bnot ", ""),
    ("shift 0.5", r"(?<![\w.])0\.5(?![\d])", "0.55"),
    ("shift 1.0", r"(?<![\w.])1\.0(?![\d])", "1.1"),
]


def candidates() -> list[tuple[str, int, str, str, str]]:
    """Every (module, line number, operator, old line, new line) one-operator mutation."""
    out = []
    for rel in MODULES:
        in_doc = False
        for no, line in enumerate((ROOT / rel).read_text(encoding="utf-8").splitlines(), 1):
            code = line.strip()
            if code.count('"""') == 1:
                in_doc = not in_doc
                continue
            if (
                in_doc
                or not code
                or code.startswith(("#", "def ", "class ", "@", "import", "from"))
            ):
                continue
            if '"' in code or "'" in code or "->" in code:
                continue  # messages and annotations: not behaviour
            for name, pattern, repl in OPERATORS:
                m = re.search(pattern, line)
                if m:
                    new = line[: m.start()] + repl + line[m.end() :]
                    out.append((rel, no, name, line, new))
    return out


def run_tests(root: Path, timeout: float) -> bool:
    """True when the qshape tests pass on the project at ``root``."""
    files = sorted(str(p.relative_to(root)) for pat in TESTS for p in root.glob(pat))
    cmd = [sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider", *files]
    env = {"PYTHONPATH": str(root), "MUJOCO_GL": "egl", "PATH": "/usr/bin:/bin"}
    try:
        res = subprocess.run(
            cmd, cwd=root, env=env, capture_output=True, timeout=timeout, check=False
        )
    except subprocess.TimeoutExpired:
        return False  # a mutant that hangs is caught (the suite would not finish)
    return res.returncode == 0


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Run the mutants; print caught/total and the missed ones."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mutants", type=int, default=40)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--timeout", type=float, default=300.0)
    ap.add_argument("--out", type=Path, default=Path("out/bench_mutation.json"))
    args = ap.parse_args(argv)
    pool = candidates()
    chosen = random.Random(args.seed).sample(pool, min(args.mutants, len(pool)))
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp) / "project"
        shutil.copytree(ROOT, work, ignore=shutil.ignore_patterns(".git", "out", "__pycache__"))
        if not run_tests(work, args.timeout):
            raise SystemExit("the qshape tests fail on the unmutated copy; fix them first")
        results = []
        for rel, no, name, _old, new in chosen:
            path = work / rel
            text = path.read_text(encoding="utf-8")
            lines = text.splitlines(keepends=True)
            lines[no - 1] = new + "\n"
            path.write_text("".join(lines), encoding="utf-8")
            t0 = time.perf_counter()
            caught = not run_tests(work, args.timeout)
            path.write_text(text, encoding="utf-8")
            results.append(
                {"file": rel, "line": no, "operator": name, "caught": caught, "new": new.strip()}
            )
            mark = "caught" if caught else "MISSED"
            print(
                f"{mark:6}  {rel}:{no}  {name:12} {new.strip()[:64]}  "
                f"({time.perf_counter() - t0:.0f} s)"
            )
            sys.stdout.flush()
    n_caught = sum(1 for r in results if r["caught"])
    print(f"caught {n_caught}/{len(results)} mutants ({len(pool)} candidates)")
    out = {"caught": n_caught, "total": len(results), "candidates": len(pool), "mutants": results}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_text(args.out, json.dumps(out, indent=2) + "\n")
    return out


if __name__ == "__main__":
    run_cli(main)
