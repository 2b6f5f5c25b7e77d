"""qshape's module graph: no import cycles, no simulator or RL imports, public API in place."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import qshape
from qshape.design import DESIGN_SUBDIR, DesignRules, Loop, TilePath, color_hex, load_section
from qshape.theory.matching import canonical_keys, clear_key_caches, evaluate_block, pack

ROOT = Path(__file__).resolve().parents[2]
PKG = ROOT / "qshape"


def _module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _imports() -> dict[str, set[str]]:
    """Every qshape module -> the qshape modules it imports (anywhere in the file)."""
    modules = {_module_name(p): p for p in PKG.rglob("*.py")}
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        deps: set[str] = set()
        tree = ast.parse(path.read_text(encoding="utf-8"))
        typing_only = {  # `if TYPE_CHECKING:` imports are for annotations, not run
            id(n)
            for block in ast.walk(tree)
            if isinstance(block, ast.If) and ast.unparse(block.test) == "TYPE_CHECKING"
            for stmt in block.body
            for n in ast.walk(stmt)
        }
        for node in ast.walk(tree):
            if id(node) in typing_only:
                continue
            if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                target = node.module
                for alias in node.names:
                    sub = f"{target}.{alias.name}"
                    deps.add(sub if sub in modules else target)
            elif isinstance(node, ast.Import):
                deps.update(a.name for a in node.names)
        graph[name] = {d for d in deps if d in modules and d != name}
    return graph


def test_no_import_cycles_between_qshape_modules() -> None:
    graph = _imports()
    # Package __init__ files only re-export: a cycle through one is no cycle of concepts.
    graph = {k: {d for d in v if d not in {"qshape", "qshape.design"}} for k, v in graph.items()}
    state: dict[str, int] = {}

    def visit(node: str, stack: list[str]) -> None:
        state[node] = 1
        for dep in sorted(graph[node]):
            if state.get(dep) == 1:
                raise AssertionError("import cycle: " + " -> ".join([*stack, node, dep]))
            if dep not in state:
                visit(dep, [*stack, node])
        state[node] = 2

    for module in sorted(graph):
        if module not in state:
            visit(module, [])
    assert "qshape.design.from_image" in graph["qshape.design.model"]
    assert not any(d.startswith("qshape.design") for d in graph["qshape.vision.extract"])


def test_qshape_imports_no_simulator_or_rl_package() -> None:
    code = (
        "import sys, qshape, qshape.design, qshape.vision.extract, qshape.synthetic.render; "
        "bad = [m for m in ('mujoco', 'gymnasium', 'envs', 'planners', 'agents') "
        "if m in sys.modules]; print(bad)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True
    )
    assert out.stdout.strip() == "[]"


def test_public_api_is_kept() -> None:
    for name in ("Design", "Slot", "render_design", "extract", "parse", "match", "assign"):
        assert hasattr(qshape, name)
    assert DESIGN_SUBDIR == "designs" and callable(load_section) and callable(color_hex)
    assert DesignRules().outline_step_mm > 0 and Loop and TilePath
    assert callable(canonical_keys) and callable(clear_key_caches)
    assert callable(evaluate_block) and callable(pack)
