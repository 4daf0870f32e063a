"""The README's Layout section names every folder of ``src/`` and ``python/motionblur/``, and
every folder it names there exists."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TREES = ("src", "python/motionblur")


def _layout() -> str:
    text = (ROOT / "README.md").read_text()
    start = text.index("\n## Layout\n")
    end = text.find("\n## ", start + 1)
    return text[start : end if end >= 0 else len(text)]


def _folders(tree: str) -> list[str]:
    base = ROOT / tree
    return sorted(
        f"{p.relative_to(ROOT).as_posix()}/"
        for p in base.rglob("*")
        if p.is_dir() and not any(part.startswith((".", "__")) for part in p.relative_to(base).parts)
    )


def test_the_layout_names_every_folder():
    section = _layout()
    named = set(re.findall(r"`([^`\s]+/)`", section))
    folders = [f for tree in TREES for f in [f"{tree}/", *_folders(tree)]]
    missing = [f for f in folders if f not in named]
    assert not missing, f"README.md, section Layout: name these folders as `path/`: {missing}"


def test_every_folder_the_layout_names_exists():
    named = set(re.findall(r"`([^`\s]+/)`", _layout()))
    stale = sorted(
        f for f in named if f.startswith(tuple(f"{t}/" for t in TREES)) and not (ROOT / f).is_dir()
    )
    assert not stale, f"README.md, section Layout, names folders that are gone: {stale}"


def test_the_paths_the_readme_gives_exist():
    text = (ROOT / "README.md").read_text()
    paths = set(re.findall(r"`((?:src|python|tests|benches|notebooks)/[^`\s]*)`", text))
    gone = sorted(p for p in paths if not (ROOT / p).exists())
    assert not gone, f"README.md names paths that do not exist: {gone}"
