"""The everyday pieces a user meets first: ``motionblur render FILE.glb`` on the command line, a
``Frame`` that shows itself in Jupyter, and ``save_exr`` refusing a name that is not ``.exr``."""

from __future__ import annotations

import io
import subprocess
import sys

import numpy as np
import pytest
from _helpers import gltf_writer as gw
from PIL import Image

import motionblur as mb
from motionblur.__main__ import main


@pytest.fixture
def glb(tmp_path):
    gl, blob = gw.animated_asset(parts=("cube", "camera"))
    return gw.write(tmp_path, "glTF-Binary", gl, blob)


def test_render_writes_the_frame_the_library_renders(glb, tmp_path, capsys):
    out = tmp_path / "out" / "cube.png"
    code = main(["render", str(glb), "--method", "accumulation", "--samples", "8", "--out", str(out),
                 "--width", "48", "--height", "36", "--option", "aa=2"])  # fmt: skip
    assert code == 0
    said = capsys.readouterr().out
    assert str(out) in said and "accumulation" in said and "48x36" in said
    scene = mb.Scene.from_gltf(glb, width=48, height=36)
    expected = mb.render(scene, "accumulation", samples=8, aa=2, error_estimate=False).to_srgb8()
    written = np.asarray(Image.open(out))
    assert written.shape == (36, 48, 4)
    assert np.array_equal(written, expected)  # the same bits as the Python call
    assert (written[..., 3] > 0).any()  # the cube is in the picture


def test_render_writes_exr_and_auto_meets_its_tolerance(glb, tmp_path, capsys):
    out = tmp_path / "cube.exr"
    assert (
        main(
            ["render", str(glb), "--out", str(out), "--tolerance", "0.02", "--width", "32", "--height", "24"]
        )
        == 0
    )
    said = capsys.readouterr().out
    assert "auto" in said and "estimated RMSE" in said
    back = mb.read_image(out)
    assert back.rgba.shape == (24, 32, 4)
    estimate = float(said.rsplit(" ", 1)[1])
    assert estimate <= 0.02


@pytest.mark.parametrize(
    ("args", "text"),
    [
        (["--out", "x.jpg"], "--out: expected a name ending in .png or .exr"),
        (["--out", "x.png", "--method", "nope"], "method: unknown method 'nope'"),
        (["--out", "x.png", "--option", "bogus=1"], "has no option 'bogus'"),
        (["--out", "x.png", "--option", "aa"], "--option: expected NAME=VALUE"),
    ],
)
def test_render_names_what_is_wrong_without_a_traceback(glb, tmp_path, capsys, args, text):
    code = main(
        [
            "render",
            str(glb),
            "--width",
            "16",
            "--height",
            "12",
            *[a.replace("x.", f"{tmp_path}/x.") for a in args],
        ]
    )
    assert code != 0
    err = capsys.readouterr().err
    assert text in err and "Traceback" not in err
    assert not list(tmp_path.glob("x.*"))


def test_render_of_a_missing_file_names_it(tmp_path, capsys):
    assert main(["render", str(tmp_path / "none.glb"), "--out", str(tmp_path / "a.png")]) == 1
    assert "no such file" in capsys.readouterr().err


def test_the_console_entry_runs_render(glb, tmp_path):
    out = tmp_path / "a.png"
    run = subprocess.run([sys.executable, "-m", "motionblur", "render", str(glb), "--method", "velocity",
                          "--out", str(out), "--width", "32", "--height", "24"],
                         capture_output=True, text=True, timeout=120)  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert out.is_file() and Image.open(out).size == (32, 24)


def test_a_frame_shows_itself_as_its_png():
    frame = mb.render(mb.SCENES["cube"](40, 30), "accumulation", samples=4)
    data = frame._repr_png_()
    assert data is not None and data.startswith(b"\x89PNG")
    assert np.array_equal(np.asarray(Image.open(io.BytesIO(data))), frame.to_srgb8())


def test_a_frame_with_nan_pixels_falls_back_to_its_repr():
    rgba = np.zeros((4, 5, 4), np.float32)
    rgba[1, 1, 0] = np.nan
    frame = mb.Frame(rgba, np.zeros((4, 5)), np.zeros((4, 5), np.int32), None)
    assert frame._repr_png_() is None
    assert repr(frame).startswith("Frame(5x4")


@pytest.mark.parametrize("name", ["f.png", "f.tif", "f", "f.exr.gz"])
def test_save_exr_writes_exr_only(tmp_path, name):
    frame = mb.Frame(np.zeros((4, 5, 4)), np.zeros((4, 5)), np.zeros((4, 5), np.int32), None)
    with pytest.raises(ValueError, match="path: save_exr writes OpenEXR files only"):
        frame.save_exr(tmp_path / name)
    assert not list(tmp_path.iterdir())
    assert frame.save_exr(tmp_path / "F.EXR").is_file()  # any case
