"""The README is the project's front page: short, true and linked to the rest. Its install lines
work from a clone (nothing is published yet), its links lead to files that exist, its table of
bounds is the differential test's, and the project layout page names every folder of ``src/`` and
``python/motionblur/`` (and only folders that exist)."""

from __future__ import annotations

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
LAYOUT = ROOT / "docs" / "guide" / "layout.md"
TREES = ("src", "python/motionblur")
#: The issue asks for a front page of about 250 lines; everything else lives in docs/.
MAX_README_LINES = 300
DOCS = sorted((ROOT / "docs").rglob("*.md"))


def _layout() -> str:
    text = LAYOUT.read_text()
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


def test_the_readme_is_a_front_page():
    text = README.read_text()
    assert len(text.splitlines()) <= MAX_README_LINES, f"README.md has {len(text.splitlines())} lines"
    for section in (
        "## Install",
        "## Quickstart",
        "## Which method when",
        "## Error you can trust",
        "## make",
    ):
        assert f"\n{section}\n" in text, section
    assert "make demo" in text and "make test" in text
    # the error control stays on the front page: the tuning/measuring split and the way to the details
    assert "Tuning and measuring are kept apart" in text and "(docs/validation.md)" in text
    assert text.index("mb.render(") < text.index("## Which method when"), "render() comes first"


def test_the_readme_installs_from_a_clone_until_a_release_is_published():
    for page in (README, ROOT / "docs" / "guide" / "install.md"):
        text = page.read_text()
        # `pip install motionblur` fails while nothing is on PyPI: the pages say so once it is true
        assert not re.search(r"^\s*pip install (motionblur|\"motionblur\[)", text, re.M), page.name
        assert re.search(r"^pip install \.", text, re.M) and "git clone" in text, page.name


def test_the_readmes_links_lead_to_files():
    text = README.read_text()
    links = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", text)
    local = [link for link in links if not re.match(r"[a-z]+://", link)]
    assert local, "the README links to the documentation"
    gone = sorted(link for link in local if not (ROOT / link).exists())
    assert not gone, f"README.md links to files that do not exist: {gone}"
    for page in DOCS:
        for link in re.findall(r"\]\(([^)#\s]+\.(?:md|png|ipynb))(?:#[^)]*)?\)", page.read_text()):
            assert (page.parent / link).exists(), f"{page.relative_to(ROOT)} links to {link}"


def test_the_readmes_bounds_are_the_differential_tests():
    sys.path.insert(0, str(ROOT / "tests" / "robustness"))
    try:
        from test_differential import BOUNDS
    finally:
        sys.path.pop(0)
    text = README.read_text()
    section = text[text.index("## Error you can trust") :]
    stated = {}
    for row in re.findall(r"^\| ([a-z_, ]+) \| ([0-9.]+) \| ([0-9]+)% \|", section, re.M):
        for method in row[0].split(", "):
            stated[method] = (float(row[1]), float(row[2]) / 100)
    assert stated == BOUNDS, "README.md's table of bounds differs from tests/robustness/test_differential.py"


def test_the_layout_names_every_folder():
    section = _layout()
    named = set(re.findall(r"`([^`\s]+/)`", section))
    folders = [f for tree in TREES for f in [f"{tree}/", *_folders(tree)]]
    missing = [f for f in folders if f not in named]
    assert not missing, (
        f"{LAYOUT.relative_to(ROOT)}, section Layout: name these folders as `path/`: {missing}"
    )


def test_every_folder_the_layout_names_exists():
    named = set(re.findall(r"`([^`\s]+/)`", _layout()))
    stale = sorted(
        f for f in named if f.startswith(tuple(f"{t}/" for t in TREES)) and not (ROOT / f).is_dir()
    )
    assert not stale, f"{LAYOUT.relative_to(ROOT)}, section Layout, names folders that are gone: {stale}"


def test_the_paths_the_readme_and_the_docs_give_exist():
    for page in [README, *DOCS]:
        paths = set(re.findall(r"`((?:src|python|tests|benches|notebooks|docs)/[^`\s]*)`", page.read_text()))
        gone = sorted(p for p in paths if not (ROOT / p).exists())
        assert not gone, f"{page.relative_to(ROOT)} names paths that do not exist: {gone}"
