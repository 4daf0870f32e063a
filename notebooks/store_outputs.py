"""Executes every notebook here and stores it with its outputs (``make notebooks``), so that GitHub
and the documentation site show the figures without anyone running them.

    PYTHONPATH=python python notebooks/store_outputs.py [NAME.ipynb ...]

The kernel runs in this folder with matplotlib's inline backend (MPLBACKEND is dropped: Agg
would show no figure). The run fails, and stores nothing for that notebook, when a cell raises
or writes to stderr (a warning a reader would see as a red box). The execution timestamps are
left out so that re-running changes a file only where an output changed. ``make test`` re-executes
the notebooks with nbmake; ``tests/api/test_notebooks_and_docs.py`` checks that they are stored
with outputs, small.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import nbformat
from nbclient import NotebookClient

HERE = Path(__file__).resolve().parent


def store(path: Path) -> int:
    nb = nbformat.read(path, as_version=4)
    NotebookClient(
        nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(HERE)}}
    ).execute()
    problems = []
    for i, cell in enumerate(nb.cells):
        cell.metadata.pop("execution", None)
        for out in cell.get("outputs", []):
            if out.get("output_type") == "stream" and out.get("name") == "stderr":
                problems.append(f"cell {i} writes to stderr: {out['text'][:300]!r}")
            if out.get("output_type") == "error":
                problems.append(f"cell {i} raised {out.get('ename')}")
    if problems:
        print(f"{path.name}: not stored\n  " + "\n  ".join(problems), file=sys.stderr)
        return 1
    nbformat.write(nb, path)
    print(f"{path.name}: stored, {path.stat().st_size / 1024:.0f} KiB")
    return 0


def main(names: list[str]) -> int:
    os.environ.pop("MPLBACKEND", None)  # the kernel inherits it: inline figures need it unset
    paths = [HERE / n for n in names] if names else sorted(HERE.glob("*.ipynb"))
    return max((store(p) for p in paths), default=0)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
