"""The notebooks end with a conclusion in words, and the documentation site shows every notebook
and documents every public module (``make docs`` builds it with ``--strict``; CI runs it)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))


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
    assert not any(c["cell_type"] == "code" and c.get("outputs") for c in cells), (
        "stored outputs: the docs execute them"
    )


def test_the_docs_site_shows_every_notebook_and_module():
    config = (ROOT / "mkdocs.yml").read_text()
    for nb in NOTEBOOKS:
        assert f"notebooks/{nb.name}" in config, f"mkdocs.yml nav lacks {nb.name}"
    assert (ROOT / "docs" / "notebooks").resolve() == (ROOT / "notebooks").resolve()
    pages = "".join(p.read_text() for p in (ROOT / "docs" / "api").glob("*.md"))
    documented = set(re.findall(r"^::: (motionblur[\w.]*)", pages, re.M))
    for module in ("scene", "raster", "render.render", "geometry", "shell", "image", "meshes",
                   "evaluation.metrics", "evaluation.reference", "interop.gltf", "interop.trimesh",
                   "interop.exr", "interop.mitsuba", "interop.pyrender"):  # fmt: skip
        assert f"motionblur.{module}" in documented, module
    makefile = (ROOT / "Makefile").read_text()
    assert re.search(r"^docs:.*\n(\t.*\n)*\t.*mkdocs build --strict", makefile, re.M)
    assert "make docs" in (ROOT / ".ci" / "run").read_text()
