"""The front page and the documentation site: snippets run, generated pages match the code."""

from __future__ import annotations

import importlib.util
import json
import re
import sys
import tomllib
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest
import yaml
from PIL import Image, ImageChops
from sybil import Sybil
from sybil.parsers.myst import PythonCodeBlockParser, SkipParser

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
README_MAX_BYTES = 12 * 1024
SNIPPET_FILES = sorted(
    [ROOT / "README.md", *DOCS.glob("*.md")], key=lambda p: p.relative_to(ROOT).as_posix()
)


def _load(name: str) -> ModuleType:
    """A script of ``docs/`` as a module (``docs`` is not a package)."""
    spec = importlib.util.spec_from_file_location(f"docs_{name}", DOCS / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def _has_python(path: Path) -> bool:
    return "```python" in path.read_text(encoding="utf-8")


@pytest.mark.parametrize(
    "path",
    [p for p in SNIPPET_FILES if _has_python(p)],
    ids=lambda p: p.relative_to(ROOT).as_posix(),
)
def test_python_snippets_run(path: Path) -> None:
    """Every Python block of the README and the docs pages runs (Sybil; skip comments kept)."""
    document = Sybil(parsers=[PythonCodeBlockParser(), SkipParser()]).parse(path)
    examples = list(document.examples())
    assert examples, f"{path.name}: no Python block found"
    for example in examples:
        example.evaluate()


def test_snippet_files_are_found() -> None:
    names = {p.relative_to(ROOT).as_posix() for p in SNIPPET_FILES if _has_python(p)}
    assert {"README.md", "docs/environment.md", "docs/qshape.md"} <= names


def test_readme_is_a_front_page() -> None:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(text.encode()) <= README_MAX_BYTES
    first_block = text.split("```bash\n", 1)[1].split("```", 1)[0]
    assert first_block.splitlines()[0].startswith("bash scripts/main.sh")
    assert first_block.splitlines()[1].startswith("bash scripts/test.sh")
    assert text.index("```bash") < text.index("\n## ")
    assert not re.search(r"\b20\d\d-\d\d-\d\d\b|\b\d\d:\d\d UTC\b", text), "dates belong in docs"
    for target in re.findall(r"\]\(([^)#]+)\)", text):
        assert (ROOT / target).exists(), f"README links to a missing {target}"


def test_task_pages_match_the_registry() -> None:
    """The committed gallery has one up-to-date page and picture per registered id, no others."""
    gen = _load("gen_tasks")
    expected, _ = gen.pages(render=False)
    assert gen.stale(expected) == []
    ids = gen.registered_ids()
    assert "MosaicAssembly-v0" in ids and "MosaicDecision6-v0" in ids
    assert {p.path.stem for p in expected} == {*ids, "index"}


def test_benchmark_page_renders_the_committed_json(tmp_path: Path) -> None:
    bench = _load("bench_page")
    report = json.loads((DOCS / "bench.json").read_text(encoding="utf-8"))
    out = bench.write_bench_table(DOCS / "bench.json", tmp_path / "table.md")
    text = out.read_text(encoding="utf-8")
    assert report["date"] in text.splitlines()[0]
    assert f"{report['machine']['cpus']} CPUs" in text.splitlines()[0]
    rows = [line for line in text.splitlines() if line.startswith("| ") and "---" not in line]
    assert len(rows) == len(report["figures"]) + 1  # header


def test_benchmark_page_renders_the_committed_ratios(tmp_path: Path) -> None:
    bench = _load("bench_page")
    report = json.loads((DOCS / "bench_env_ratios.json").read_text(encoding="utf-8"))
    text = bench.write_ratio_table(DOCS / "bench_env_ratios.json", tmp_path / "r.md").read_text(
        encoding="utf-8"
    )
    rows = [line for line in text.splitlines() if line.startswith("| ") and "---" not in line]
    assert len(rows) == len(report["ratios"]) + 1  # header
    for name, r in report["ratios"].items():
        row = next(line for line in rows if line.startswith(f"| {name} |"))
        assert f"| {r['ratio']:.2f} |" in row and f"<= {r['target']:g}" in row


def test_benchmark_page_opens_on_figures_that_hold_across_machines(tmp_path: Path) -> None:
    """The glance table: targets of portable figures only, the ratios, each run's load."""
    bench = _load("bench_page")
    report = json.loads((DOCS / "bench.json").read_text(encoding="utf-8"))
    ratios = json.loads((DOCS / "bench_env_ratios.json").read_text(encoding="utf-8"))
    text = bench.write_glance_table(dst=tmp_path / "g.md").read_text(encoding="utf-8")
    assert "at the start" in text.splitlines()[0] and "at the end" in text.splitlines()[0]
    rows = [line for line in text.splitlines() if line.startswith("| ") and "---" not in line]
    names = [row.split(" | ")[1] for row in rows[1:]]
    figures = [bench.Figure(**f) for f in report["figures"]]
    portable = [f.name for f in figures if f.passed is not None and bench.portable(f)]
    assert names[: len(portable)] == portable and len(names) == len(portable) + len(
        ratios["ratios"]
    )
    assert not any("steps per" in n or "ms" in n.split() for n in names)
    assert any(f.passed is not None and not bench.portable(f) for f in figures)
    assert (DOCS / "img" / "bench_overview.png").stat().st_size < 1_000_000


def test_design_gallery_covers_every_family_and_the_named_failures() -> None:
    """The random-designs page's pictures: outcomes per family, the page's failing designs."""
    gallery = _load("gen_design_gallery")
    data = json.loads(gallery.RESULTS.read_text(encoding="utf-8"))
    played = {(d["level"], d["design"]) for d in data["designs"]}
    assert {(c.level, c.design) for c in gallery.NAMED} <= played
    families = {s["family"] for d in data["designs"] for s in d["slot_outcomes"] if s["filled"]}
    assert families == set(gallery.SHAPE_FAMILIES)
    for d in data["designs"]:
        assert d["correct"] == sum(s["filled"] for s in d["slot_outcomes"]) <= d["slots"]
    text = (DOCS / "random_designs.md").read_text(encoding="utf-8")
    for png in (gallery.FAMILIES_PNG, gallery.DESIGNS_PNG):
        assert f"img/{png.name}" in text and png.stat().st_size < gallery.MAX_BYTES
        with Image.open(png) as im:
            assert im.format == "PNG" and min(im.size) > 300


def test_lock_pins_every_dependency() -> None:
    """``requirements.lock`` pins every dependency of pyproject.toml (with the extras)."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    wanted = list(project["dependencies"])
    for extra in project["optional-dependencies"].values():
        wanted += extra
    lock = (ROOT / "requirements.lock").read_text(encoding="utf-8")
    pinned = {
        m.group(1).lower().replace("_", "-"): m.group(2)
        for m in re.finditer(r"^([A-Za-z0-9_.\-]+)==(\S+)", lock, re.MULTILINE)
    }
    for req in wanted:
        name = re.split(r"[\[<>=!~; ]", req, maxsplit=1)[0].lower().replace("_", "-")
        assert name in pinned, f"{name} is not pinned in requirements.lock"
    assert pinned["torch"] == "2.13.0+cpu"
    assert pinned["mujoco"] == "3.17.0"


def test_api_reference_lists_every_package() -> None:
    """The API reference walks every top-level package that pyproject.toml ships."""
    find = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]
    patterns = find["setuptools"]["packages"]["find"]["include"]
    packages = {p.rstrip("*") for p in patterns}
    listed = set((DOCS / "api.md").read_text(encoding="utf-8").split())
    assert packages <= listed, f"missing from docs/api.md: {sorted(packages - listed)}"


def test_license_and_citation() -> None:
    license_text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert "Apache License" in license_text and "Version 2.0, January 2004" in license_text
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    assert project["license"] == "Apache-2.0"
    assert project["license-files"] == ["LICENSE"]
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))
    assert cff["cff-version"] == "1.2.0" and cff["license"] == "Apache-2.0"
    titles = [r["title"] for r in cff["references"]]
    assert "2D qualitative shape matching applied to ceramic mosaic assembly" in titles


def test_changelog_states_the_version_rule() -> None:
    text = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    assert "## When an id's version changes" in text
    gen = _load("gen_tasks")
    for env_id in gen.registered_ids():
        assert re.fullmatch(r"v\d+", env_id.rsplit("-", 1)[1]), env_id
        assert f"`{env_id}`" in text, f"{env_id} has no entry in the changelog"


def test_results_file_is_sourced_and_covers_the_ladder() -> None:
    """``docs/results.json``: every row names a command, a date and a source that exists; every
    rung has a random row and a scripted or learned one (the cards' results at a glance)."""
    results = _load("gen_results")
    gen = _load("gen_tasks")
    rows = results.load_results()
    ids = set(gen.registered_ids())
    for r in rows:
        assert r.task in ids, f"{r.task} is not registered"
        assert 0.0 <= r.success <= 1.0 and 0.0 <= r.filled <= 1.0
        assert re.fullmatch(r"20\d\d-\d\d-\d\d", r.date), r.date
        assert r.command.startswith(("python ", "bash ")) and r.time
        page = r.source.split(" ")[0]
        assert (ROOT / page).is_file(), f"{r.task} {r.policy}: no source {page}"
    for task in yaml_tasks():
        kinds = {r.kind for r in results.rows_for(task, rows)}
        assert "random" in kinds and kinds & {"scripted", "learned"}, f"{task}: {kinds}"


def yaml_tasks() -> list[str]:
    """The ``-v0`` ids of the bundled rungs."""
    return [
        yaml.safe_load(p.read_text(encoding="utf-8"))["id"]
        for p in ROOT.glob("configs/tasks/*.yaml")
    ]


def test_committed_animations_move_and_are_small() -> None:
    """Each card's GIF is an animation (many distinct frames), under the size limit."""
    anim = _load("gen_animations")
    for env_id in anim.ACTORS:
        path = DOCS / "tasks" / "img" / f"{env_id}.gif"
        assert path.stat().st_size <= anim.MAX_BYTES
        with Image.open(path) as gif:
            assert 10 <= gif.n_frames <= anim.MAX_FRAMES, (env_id, gif.n_frames)
            gif.seek(0)
            first = gif.convert("RGB")
            gif.seek(gif.n_frames - 1)
            last = gif.convert("RGB")
        assert ImageChops.difference(first, last).getbbox() is not None, f"{env_id} is still"


def test_animation_frames_are_thinned_evenly(tmp_path: Path) -> None:
    anim = _load("gen_animations")
    frames = [np.full((8, 16, 3), i, np.uint8) for i in range(100)]
    kept = anim.thin(frames, 24)
    assert len(kept) == 24 and kept[0][0, 0, 0] == 0 and kept[-1][0, 0, 0] == 99
    assert len(anim.thin(frames[:5], 24)) == 5
    size = anim.write_gif(kept, tmp_path / "a.gif")
    assert 0 < size == (tmp_path / "a.gif").stat().st_size
