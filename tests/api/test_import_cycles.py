"""No two files of the project use each other, directly or round a longer loop.

The Python package and the Rust crate are checked apart, so a failure says whose loop it is.
How a file's uses are read (imports, ``use`` paths, re-exports, test code left out) is in
``tests/_helpers/import_graph.py``; ``python tests/_helpers/import_graph.py`` prints both graphs'
cycles. The tests at the bottom hold the reader to small trees written out here.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from _helpers.import_graph import cycles, describe, python_graph, rust_graph

ROOT = Path(__file__).resolve().parents[2]


def _report(graph, found) -> str:
    return "\n".join(f"cycle {i + 1}:\n{describe(graph, c)}" for i, c in enumerate(found))


def test_no_import_cycle_among_the_python_modules():
    graph = python_graph(ROOT / "python" / "motionblur", ROOT)
    assert len(graph) > 20 and sum(map(len, graph.values())) > 50  # the package was read
    found = cycles(graph)
    if found:
        pytest.fail("Python modules that import each other:\n" + _report(graph, found), pytrace=False)


def test_no_use_cycle_among_the_rust_files():
    graph = rust_graph(ROOT / "src", ROOT)
    assert len(graph) > 20 and sum(map(len, graph.values())) > 50  # the crate was read
    found = cycles(graph)
    if found:
        pytest.fail("Rust files that use each other:\n" + _report(graph, found), pytrace=False)


# ---------------------------------------------------------------- the reader on small trees


def _tree(root: Path, files: dict[str, str]) -> Path:
    for name, text in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return root


def test_python_imports_at_any_depth_and_from_packages(tmp_path):
    pkg = _tree(
        tmp_path,
        {
            "p/__init__.py": "from . import a\n",
            "p/a.py": "from .sub import helper\n",
            "p/sub/__init__.py": "from ._impl import helper\n",
            "p/sub/_impl.py": "def helper():\n    from .. import a  # a lazy import still ties the files\n",
            "p/_core.pyi": "",
            "p/b.py": "from . import _core\nimport p.sub._impl\n",
        },
    )
    g = python_graph(pkg / "p", tmp_path)
    assert g["p/a.py"] == {"p/sub/__init__.py": {"helper"}}
    assert g["p/sub/_impl.py"] == {"p/a.py": {"a"}}
    assert set(g["p/b.py"]) == {"p/_core.pyi", "p/sub/_impl.py"}
    assert cycles(g) == [["p/a.py", "p/sub/__init__.py", "p/sub/_impl.py"]]


def test_rust_paths_resolve_to_files_and_follow_re_exports(tmp_path):
    crate = _tree(
        tmp_path,
        {
            "src/lib.rs": "mod error;\npub mod a;\npub mod b;\npub use error::Error;\n",
            "src/error.rs": "pub struct Error;\n",
            "src/a.rs": "mod inner;\npub use inner::Thing;\nuse crate::Error;\npub fn f() -> Thing { inner::make() }\n",
            "src/a/inner.rs": "pub struct Thing;\npub fn make() -> Thing { Thing }\n",
            "src/b/mod.rs": (
                "mod c;\npub use c::*;\n"
                'pub fn g() { let s = "crate::a::f()"; /* crate::a::f() */ }\n'
                "#[cfg(test)]\nmod tests {\n    use super::*;\n    use crate::a::f;\n}\n"
            ),
            "src/b/c.rs": "use crate::{a::{self, Thing}, Error};\npub fn h() -> Thing { a::f() }\n",
        },
    )
    g = rust_graph(crate / "src", tmp_path)
    # crate::Error is defined in error.rs, re-exported by lib.rs; Thing in a/inner.rs through a.rs
    assert g["src/b/c.rs"] == {"src/error.rs": {"Error"}, "src/a/inner.rs": {"Thing"}, "src/a.rs": {"a", "f"}}
    assert g["src/a.rs"] == {"src/error.rs": {"Error"}, "src/a/inner.rs": {"Thing", "make"}}
    # strings, comments, re-exports that the file does not use and test modules make no edge
    assert g["src/b/mod.rs"] == {} and g["src/lib.rs"] == {}
    assert cycles(g) == []


def test_rust_super_in_a_child_module_and_a_loop(tmp_path):
    crate = _tree(
        tmp_path,
        {
            "src/lib.rs": "pub mod r;\n",
            "src/r/mod.rs": "mod t;\nmod s;\npub const N: usize = 4;\npub fn run() { t::go() }\n",
            "src/r/t.rs": "use super::N;\npub fn go() { super::s::Back::new(); }\n",
            "src/r/s.rs": "pub struct Back;\nimpl Back { pub fn new() -> Self { Back } }\n",
        },
    )
    g = rust_graph(crate / "src", tmp_path)
    assert g["src/r/t.rs"] == {"src/r/mod.rs": {"N"}, "src/r/s.rs": {"Back"}}
    assert g["src/r/mod.rs"] == {"src/r/t.rs": {"go"}}
    assert cycles(g) == [["src/r/mod.rs", "src/r/t.rs"]]
