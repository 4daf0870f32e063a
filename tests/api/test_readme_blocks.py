"""Every Python block of the README and of the documentation pages runs as written, each on its own
(as a reader copies one), in a fresh folder."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
BLOCKS = [
    (page.relative_to(ROOT).as_posix(), code)
    for page in PAGES
    for code in re.findall(r"```python\n(.*?)```", page.read_text(), re.S)
]


def _params():
    for i, (page, code) in enumerate(BLOCKS):
        first = next(line for line in code.splitlines() if line.strip() and not line.startswith("import"))
        marks = [pytest.mark.mitsuba] if "reference.mitsuba" in code or "to_mitsuba_dict" in code else []
        marks += [pytest.mark.pyrender] if "pyrender" in code else []
        name = re.sub(r"[^a-z]+", "_", f"{Path(page).stem}_{first}".lower())[:40]
        yield pytest.param(page, code, id=f"block{i + 1}-{name}", marks=marks)


def test_the_readme_and_the_docs_have_their_blocks():
    readme = [code for page, code in BLOCKS if page == "README.md"]
    assert len(readme) >= 1, "the README's quickstart"
    assert len(BLOCKS) >= 8, "the guide's and the methods' examples"


@pytest.mark.parametrize(("page", "code"), list(_params()))
def test_a_block_runs_as_written(page, code, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    exec(compile(code, page, "exec"), {"__name__": "__readme__"})
