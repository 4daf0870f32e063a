"""The notebooks end with a conclusion in words and are stored executed (their figures show on
GitHub and on the site; ``make test`` re-executes them with nbmake), and the documentation site
shows every notebook, documents every public module and builds with warnings as errors
(``make docs``; CI runs it)."""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
#: A stored notebook stays small enough to read on GitHub and to keep in git.
MAX_NOTEBOOK_BYTES = 1_000_000


def test_there_are_notebooks():
    assert len(NOTEBOOKS) >= 5


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_a_notebook_ends_with_a_conclusion_in_words(path):
    cells = json.loads(path.read_text())["cells"]
    last = cells[-1]
    text = "".join(last["source"])
    assert last["cell_type"] == "markdown" and text.startswith("## Conclusion"), f"{path.name}: last cell"
    words = re.findall(r"[A-Za-z]+", text)
    assert len(words) >= 60, f"{path.name}: the conclusion has {len(words)} words"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_a_notebook_is_stored_executed_with_its_figures_and_small(path):
    cells = [c for c in json.loads(path.read_text())["cells"] if c["cell_type"] == "code"]
    unrun = [i for i, c in enumerate(cells) if c.get("execution_count") is None]
    assert not unrun, f"{path.name}: code cells {unrun} were not run (make notebooks stores them executed)"
    outputs = [o for c in cells for o in c.get("outputs", [])]
    assert any("image/png" in o.get("data", {}) for o in outputs), f"{path.name}: no figure stored"
    bad = [o.get("ename") or o["text"][:120] for o in outputs
           if o["output_type"] == "error" or o.get("name") == "stderr"]  # fmt: skip
    assert not bad, f"{path.name}: stored errors or stderr (a red box for readers): {bad}"
    assert path.stat().st_size < MAX_NOTEBOOK_BYTES, f"{path.name}: {path.stat().st_size} bytes"
    counts = [c["execution_count"] for c in cells]
    assert counts == list(range(1, len(cells) + 1)), f"{path.name}: executed out of order: {counts}"


def test_the_docs_site_shows_every_notebook_and_module():
    config = (ROOT / "mkdocs.yml").read_text()
    for nb in NOTEBOOKS:
        assert f"notebooks/{nb.name}" in config, f"mkdocs.yml nav lacks {nb.name}"
    assert (ROOT / "docs" / "notebooks").resolve() == (ROOT / "notebooks").resolve()
    pages = "".join(p.read_text() for p in (ROOT / "docs" / "api").glob("*.md"))
    documented = set(re.findall(r"^::: (motionblur[\w.]*)", pages, re.M))
    for module in ("scene", "raster", "render.render", "exact", "geometry", "shell", "image", "meshes",
                   "evaluation.metrics", "evaluation.reference", "interop.gltf", "interop.trimesh",
                   "interop.exr", "interop.mitsuba", "interop.pyrender"):  # fmt: skip
        assert f"motionblur.{module}" in documented, module
    makefile = (ROOT / "Makefile").read_text()
    assert re.search(r"^docs:.*\n(\t.*\n)*\t.*mkdocs build --strict", makefile, re.M)
    assert "make docs" in (ROOT / ".ci" / "run").read_text()


def test_the_docs_render_one_docstring_style_and_show_the_stored_notebooks():
    config = (ROOT / "mkdocs.yml").read_text()
    style = re.search(r"docstring_style:\s*(\S+)", config)
    assert style and style.group(1) in ("google", "numpy", "sphinx"), "mkdocstrings needs a docstring style"
    assert re.search(r"mkdocs-jupyter:\n(\s+.*\n)*?\s+execute: false", config), (
        "the notebooks are stored executed: the site shows them as stored"
    )


def test_every_page_in_the_nav_exists_and_every_page_is_in_the_nav():
    config = (ROOT / "mkdocs.yml").read_text()
    nav = re.findall(r"^\s+- [^:\n]+: (\S+\.(?:md|ipynb))$", config, re.M)
    missing = [p for p in nav if not (ROOT / "docs" / p).is_file()]
    assert not missing, missing
    pages = sorted(p.relative_to(ROOT / "docs").as_posix() for p in (ROOT / "docs").rglob("*.md")
                   if "notebooks" not in p.parts)  # fmt: skip
    assert set(pages) <= set(nav), f"pages outside the nav: {sorted(set(pages) - set(nav))}"


def test_the_home_page_is_its_own_not_the_readme_pasted():
    home = (ROOT / "docs" / "index.md").read_text()
    assert "README.md" not in home
    assert len(re.findall(r"^# ", home, re.M)) == 1, "one title"


def test_the_docs_target_fails_on_warnings_and_on_error_lines():
    makefile = (ROOT / "Makefile").read_text()
    recipe = re.search(r"^docs:.*\n((?:\t.*\n)+)", makefile, re.M).group(1)
    assert "--strict" in recipe and "pipefail" in recipe
    assert re.search(r"grep .*ERROR", recipe), "the docs target checks its output for ERROR lines"


def _hooks():
    sys.path.insert(0, str(ROOT / "docs"))
    try:
        import hooks
    finally:
        sys.path.pop(0)
    return hooks


def test_the_benchmarks_page_says_how_to_make_them_without_bench_output(tmp_path):
    text = _hooks().bench_results(tmp_path / "out" / "bench", tmp_path)
    assert "make bench" in text and "|" not in text


def test_the_benchmarks_page_shows_the_last_runs_tables(tmp_path):
    bench = tmp_path / "out" / "bench"
    (bench / "error_control").mkdir(parents=True)
    (bench / "raster.md").write_text("# Raster\n\n| faces | ms |\n|---|---|\n| 5120 | 3.5 |\n")
    (bench / "results.md").write_text("# Speed against error\n\n## cube\n\n| method | ms |\n|---|---|\n")
    (bench / "error_control" / "results.md").write_text("# measuring set\n\n| a | b |\n|---|---|\n")
    text = _hooks().bench_results(bench, tmp_path)
    order = [
        text.index(f"### `out/bench/{n}`") for n in ("results.md", "error_control/results.md", "raster.md")
    ]
    assert order == sorted(order), "the report's own table first"
    assert "| 5120 | 3.5 |" in text
    assert "\n#### Speed against error" in text and "\n##### cube" in text  # headings under the file's
    assert "\n# " not in text and "\n## Speed" not in text
