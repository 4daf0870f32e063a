"""EXR files through the OpenEXR bindings: linear float RGBA with depth, ids and velocity as
channels, bit-exact both ways; PNGs read back; the metrics read both from paths."""

from __future__ import annotations

import numpy as np
import OpenEXR
import pytest

import motionblur as mb


def _moving_frame() -> mb.Frame:
    cam = mb.Camera(mb.look_at((0, 0.3, 4), (0, 0, 0)), 0.7, 48, 36)
    cube = mb.Object(mb.meshes.box((0.7, 0.7, 0.7)), color=(0.9, 0.3, 0.1),
                     motion=mb.Motion.linear([-0.6, 0, 0], [0.6, 0, 0]))  # fmt: skip
    v, f = mb.meshes.icosphere(2)
    still = mb.Object((v * 0.4 + [1.3, 0.0, 0.0], f), color=(0.2, 0.5, 0.9, 0.5), motion=None)
    return mb.render(mb.Scene([cube, still], cam), "opaque_image", aa=2)


def test_a_frame_round_trips_bit_exactly(tmp_path):
    frame = _moving_frame()
    assert np.isinf(frame.depth).any() and (frame.ids == -1).any() and (frame.velocity != 0).any()
    path = frame.save_exr(tmp_path / "deep" / "frame.exr")
    back = mb.read_image(path)
    for name in ("rgba", "depth", "ids", "velocity"):
        a, b = getattr(frame, name), getattr(back, name)
        assert a.dtype == b.dtype and a.shape == b.shape, name
        np.testing.assert_array_equal(
            a.view(np.uint32), b.view(np.uint32), err_msg=name
        )  # bits, inf and -1 too
    assert back.stats["method"] == "opaque_image" and back.stats["options"] == {"aa": 2}


def test_the_channels_are_named_for_other_tools(tmp_path):
    frame = _moving_frame()
    frame.save_exr(tmp_path / "f.exr")
    ch = OpenEXR.File(str(tmp_path / "f.exr"), separate_channels=True).channels()
    assert set(ch) == {"R", "G", "B", "A", "Z", "id", "velocity.X", "velocity.Y"}
    np.testing.assert_array_equal(ch["A"].pixels, frame.rgba[..., 3])
    np.testing.assert_array_equal(ch["Z"].pixels, frame.depth)
    assert ch["id"].pixels.dtype == np.uint32 and ch["R"].pixels.dtype == np.float32


def test_strided_arrays_are_written_as_they_read(tmp_path):
    # the bindings read a strided view wrongly: the writer copies each plane contiguously first
    big = np.random.default_rng(0).random((20, 30, 8)).astype(np.float32)
    rgba, depth, vel = big[::2, ::3, 1:5], big[::2, ::3, 0], big[::2, ::3, 6:8]
    ids = np.arange(200, dtype=np.int32).reshape(10, 20)[:, ::2]
    path = mb.interop.exr.write_exr(tmp_path / "s.exr", rgba, depth, ids, vel)
    back = mb.interop.exr.read_exr(path)
    for got, want in (
        (back["rgba"], rgba),
        (back["depth"], depth),
        (back["ids"], ids),
        (back["velocity"], vel),
    ):
        np.testing.assert_array_equal(got, want)


def test_an_rgb_exr_from_elsewhere_reads_with_alpha_one(tmp_path):
    rgb = np.random.default_rng(1).random((5, 7, 3)).astype(np.float32)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    chans = {c: np.ascontiguousarray(rgb[..., i]) for i, c in enumerate("RGB")}
    OpenEXR.File(header, chans).write(str(tmp_path / "rgb.exr"))
    back = mb.read_image(tmp_path / "rgb.exr")
    np.testing.assert_array_equal(back.rgba[..., :3], rgb)
    assert (back.rgba[..., 3] == 1).all() and np.isinf(back.depth).all() and (back.ids == -1).all()


def test_a_png_reads_back_to_the_same_8_bit_image(tmp_path):
    frame = _moving_frame()
    frame.save_png(tmp_path / "f.png")
    back = mb.read_image(tmp_path / "f.png")
    np.testing.assert_array_equal(back.to_srgb8(), frame.to_srgb8())  # quantised once, then stable
    assert np.abs(back.rgba - frame.rgba).max() < 0.02


def test_metrics_read_image_paths(tmp_path):
    a, b = _moving_frame(), mb.render(mb.SCENES["cube"](48, 36), "accumulation", samples=4)
    b = mb.Frame(b.rgba, b.depth, b.ids, b.velocity)
    pa, pb = a.save_exr(tmp_path / "a.exr"), b.save_exr(tmp_path / "b.exr")
    assert mb.metrics.rmse(pa, pb) == mb.metrics.rmse(a, b)
    assert mb.metrics.rmse(str(pa), b) == mb.metrics.rmse(a, b)


def test_bad_paths_are_named(tmp_path):
    with pytest.raises(ValueError, match="path: expected an .exr or .png file"):
        mb.read_image(tmp_path / "a.jpg")
    with pytest.raises(FileNotFoundError, match="path: no such file"):
        mb.read_image(tmp_path / "missing.exr")
    with pytest.raises(ValueError, match=r"depth: expected shape \(2, 3\)"):
        mb.interop.exr.write_exr(tmp_path / "x.exr", np.zeros((2, 3, 4), np.float32), depth=np.zeros((3, 2)))
