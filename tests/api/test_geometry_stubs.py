"""The geometry section of _core.pyi describes exactly the compiled geometry names."""

from __future__ import annotations

import re
from pathlib import Path

import motionblur
from motionblur import _core

STUB = Path(motionblur.__file__).with_name("_core.pyi")


def geometry_section() -> str:
    text = STUB.read_text()
    start = text.index("# --- geometry")
    return text[start : text.index("# --- end geometry")]


def test_every_stubbed_geometry_name_is_compiled():
    sec = geometry_section()
    names = re.findall(r"^(?:def|class) (\w+)", sec, flags=re.M) + re.findall(r"^(\w+): int", sec, flags=re.M)
    assert {"_Mesh", "_ContourTable", "contour_edges", "motion_volume", "spin_volume", "LEADING"} <= set(
        names
    )
    for n in names:
        assert hasattr(_core, n), n


def test_every_compiled_geometry_name_is_stubbed():
    sec = geometry_section()
    for n in (
        "_Mesh",
        "_ContourTable",
        "contour_edges",
        "motion_volume",
        "spin_volume",
        "LEADING",
        "TRAILING",
        "JOINING",
    ):
        assert hasattr(_core, n)
        assert re.search(rf"^(def|class) {n}\b|^{n}: int", sec, flags=re.M), n
    methods = re.findall(r"^    def (\w+)", sec, flags=re.M)
    for cls in (_core._Mesh, _core._ContourTable):
        for m in (x for x in dir(cls) if not x.startswith("_")):
            assert m in methods, f"{cls.__name__}.{m}"
