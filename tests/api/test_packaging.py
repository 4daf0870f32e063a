"""Packaging: one version source, the licence and changelog, extras that resolve, the console
script, classifiers, a stripped extension, and the wheel that carries all of it.

The wheel test builds a real wheel with maturin (the release profile's artefacts are reused
from ``make build``, so it mostly links). ``make lint`` also resolves ``.[all]`` with plain pip
(``pip install --dry-run``), which needs the package index.
"""

from __future__ import annotations

import email
import importlib.metadata
import os
import re
import struct
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

import motionblur as mb

ROOT = Path(__file__).resolve().parents[2]

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib  # type: ignore[no-redef]


def _pyproject() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())


def _cargo_version() -> str:
    return re.search(r'^version\s*=\s*"([^"]+)"', (ROOT / "Cargo.toml").read_text(), re.M).group(1)


def test_one_version_source():
    project = _pyproject()["project"]
    assert "version" not in project and "version" in project["dynamic"], (
        "the version lives in Cargo.toml only"
    )
    assert mb.__version__ == _cargo_version() == importlib.metadata.version("motionblur")


def test_licence_changelog_and_classifiers():
    assert (ROOT / "LICENSE").read_text().startswith("MIT License")
    assert "## Unreleased" in (ROOT / "CHANGELOG.md").read_text()
    project = _pyproject()["project"]
    assert project["license"] == {"file": "LICENSE"}
    classifiers = project["classifiers"]
    for c in ("License :: OSI Approved :: MIT License", "Typing :: Typed", "Programming Language :: Rust"):
        assert c in classifiers
    assert project["scripts"] == {"motionblur": "motionblur.__main__:main"}


def test_extras_by_purpose_and_all_is_their_union():
    extras = _pyproject()["project"]["optional-dependencies"]
    assert {"reference", "metrics", "pyrender", "interop", "meshes", "bench", "all"} <= set(extras)
    assert "peers" not in extras
    others = sorted(set(extras) - {"all", "dev"})
    assert extras["all"] == [
        f"motionblur[{','.join(o for o in ['reference', 'metrics', 'pyrender', 'interop', 'meshes', 'bench', 'video'])}]"
    ]
    # blender (bpy) is left out of `all`: its wheels are for Python 3.11 only
    assert set(others) == {
        "reference",
        "metrics",
        "pyrender",
        "interop",
        "meshes",
        "bench",
        "blender",
        "video",
    }
    # the MP4 preview of motionblur dataset: imageio-ffmpeg ships the ffmpeg it runs
    assert any(r.startswith("imageio-ffmpeg") for r in extras["video"])
    # the real meshes of the report come with the bench, not with the library
    assert "motionblur[reference,metrics,meshes]" in extras["bench"]
    # pyrender 0.1.45 pins PyOpenGL==3.1.0: an extra asking for a newer PyOpenGL cannot resolve
    for name, reqs in extras.items():
        assert not any(r.lower().startswith("pyopengl") for r in reqs), name
    assert any(r.startswith("mitsuba") for r in extras["reference"])
    assert any(r.startswith("flip-evaluator") for r in extras["metrics"])
    assert {"pygltflib", "OpenEXR", "trimesh"} <= {re.split(r"[<>=]", r)[0] for r in extras["interop"]}
    # dev is for working on the project (make installs requirements-dev.txt, which holds it)
    dev_reqs = {
        re.split(r"[<>=]", r)[0]
        for r in (Path(__file__).parents[2] / "requirements-dev.txt").read_text().split()
    }
    assert {re.split(r"[<>=]", r)[0] for r in extras["dev"]} <= dev_reqs


def test_console_script_prints_the_version():
    script = Path(sys.executable).parent / "motionblur"
    assert script.exists(), "pip (maturin develop) installs the motionblur script"
    out = subprocess.run([str(script), "--version"], capture_output=True, text=True, check=True).stdout
    assert out.strip() == f"motionblur {mb.__version__}"
    out = subprocess.run(
        [sys.executable, "-m", "motionblur", "--version"], capture_output=True, text=True, check=True
    )
    assert out.stdout.strip() == f"motionblur {mb.__version__}"
    # importing the package does not load motionblur.__main__ (runpy would warn that it is loaded)
    assert "RuntimeWarning" not in out.stderr, out.stderr


def _sections(path: Path) -> set[str]:
    """Names of the sections of an ELF64 little-endian shared object."""
    data = path.read_bytes()
    assert data[:4] == b"\x7fELF" and data[4] == 2 and data[5] == 1, "an ELF64 little-endian file"
    shoff = struct.unpack_from("<Q", data, 0x28)[0]
    shentsize, shnum, shstrndx = struct.unpack_from("<HHH", data, 0x3A)
    heads = [struct.unpack_from("<IIQQQQIIQQ", data, shoff + i * shentsize) for i in range(shnum)]
    strtab = heads[shstrndx]
    names = data[strtab[4] : strtab[4] + strtab[5]]
    return {names[h[0] : names.index(b"\0", h[0])].decode() for h in heads}


def test_the_installed_extension_is_stripped():
    sections = _sections(Path(mb._core.__file__))
    assert ".dynsym" in sections  # the sanity of the reader: a shared object has dynamic symbols
    assert ".symtab" not in sections and not any(s.startswith(".debug") for s in sections)


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("wheel")
    env = {**os.environ, "VIRTUAL_ENV": str(Path(sys.executable).parents[1])}
    maturin = Path(sys.executable).parent / "maturin"
    subprocess.run(
        [str(maturin), "build", "--release", "--quiet", "--out", str(out)], cwd=ROOT, env=env, check=True,
        capture_output=True,
    )  # fmt: skip
    (whl,) = out.glob("motionblur-*.whl")
    return whl


def test_the_wheel_carries_licence_script_metadata_and_a_stripped_module(wheel, tmp_path):
    with zipfile.ZipFile(wheel) as z:
        names = z.namelist()
        dist = next(n.split("/")[0] for n in names if n.endswith(".dist-info/METADATA"))
        assert any(n.startswith(dist) and n.endswith("LICENSE") for n in names), names
        assert "motionblur/py.typed" in names and "motionblur/_core.pyi" in names
        # the report's meshes ship as package data, with their sources and terms
        assert {"motionblur/data/bunny.ply", "motionblur/data/ant.ply", "motionblur/data/README.md"} <= set(
            names
        )
        entry = z.read(f"{dist}/entry_points.txt").decode()
        assert "motionblur=motionblur.__main__:main" in entry.replace(" ", ""), entry
        meta = email.message_from_bytes(z.read(f"{dist}/METADATA"))
        (so,) = [n for n in names if re.match(r"motionblur/_core\..*so$", n)]
        (tmp_path / "core.so").write_bytes(z.read(so))
    assert meta["Version"] == _cargo_version()
    assert "Typing :: Typed" in meta.get_all("Classifier")
    assert {"reference", "metrics", "pyrender", "interop", "bench", "all"} <= set(
        meta.get_all("Provides-Extra")
    )
    assert ".symtab" not in _sections(tmp_path / "core.so")
