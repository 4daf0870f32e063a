"""Every Python block of the README runs as written, each on its own (as a reader copies one),
in a fresh folder."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BLOCKS = re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), re.S)


def _params():
    for i, code in enumerate(BLOCKS):
        first = next(line for line in code.splitlines() if line.strip() and not line.startswith("import"))
        marks = [pytest.mark.mitsuba] if "reference.mitsuba" in code or "to_mitsuba_dict" in code else []
        marks += [pytest.mark.pyrender] if "pyrender" in code else []
        yield pytest.param(
            code, id=f"block{i + 1}-{re.sub(r'[^a-z]+', '_', first.lower())[:30]}", marks=marks
        )


def test_the_readme_has_its_blocks():
    assert len(BLOCKS) >= 5


@pytest.mark.parametrize("code", list(_params()))
def test_a_readme_block_runs_as_written(code, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "README.md", "exec"), {"__name__": "__readme__"})
