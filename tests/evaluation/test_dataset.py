"""``make_dataset`` / ``motionblur dataset``: files and metadata per frame, resumable, bit-stable,
built-in scenes re-timed exactly, glTF input, the CLI, and Dask frames equal to the serial run."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from _helpers import gltf_writer as gw

import motionblur as mb
from motionblur.dataset import make_dataset, retime

KW = dict(
    frames=(0, 3), width=64, height=48, outputs=["blurred", "sharp", "flow", "depth", "ids"], progress=False
)
FRAME_KEYS = {"camera", "shutter", "method", "options", "error_estimate", "seed", "library_version", "frame"}


def _arrays(folder: Path, k: int) -> dict:
    f = mb.read_image(folder / f"frame_{k:06d}.exr")
    base = {"rgba": f.rgba, "depth": f.depth, "ids": f.ids, "velocity": f.velocity}
    return base | {f"extra.{n}": np.asarray(v) for n, v in (f.outputs or {}).get("channels", {}).items()}


def _files(folder: Path) -> dict:
    return {p.name: (p.stat().st_mtime_ns, p.read_bytes()) for p in sorted(folder.iterdir())}


def test_files_metadata_resume_and_same_bits(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    run = make_dataset("cube", a, shake=0.5, seed=7, **KW)
    assert run["rendered"] == [0, 1, 2] and run["skipped"] == []
    names = {p.name for p in a.iterdir()}
    for k in range(3):
        assert {f"frame_{k:06d}.{e}" for e in ("exr", "png", "json")} <= names
        meta = json.loads((a / f"frame_{k:06d}.json").read_text())
        assert FRAME_KEYS <= meta.keys() and meta["frame"] == k and meta["seed"] == 7
        assert meta["library_version"] == mb.__version__
        assert meta["shutter"]["window"] == pytest.approx([k / 3, k / 3 + 0.5 / 3])
        assert isinstance(meta["error_estimate"], float)
    assert {"dataset.json", "preview.gif"} <= names
    assert not [n for n in names if ".tmp" in n]
    ex = _arrays(a, 0)
    assert {"rgba", "depth", "ids"} <= ex.keys()
    assert any(n.startswith("extra.sharp.0.") for n in ex) and any(n.startswith("extra.flow.0.") for n in ex)
    # frames differ (the cube moves across the clip)
    assert not np.array_equal(ex["rgba"], _arrays(a, 2)["rgba"])

    before = _files(a)
    again = make_dataset("cube", a, shake=0.5, seed=7, **KW)
    assert again["rendered"] == [] and again["skipped"] == [0, 1, 2]
    assert _files(a) == before  # nothing rewritten, not even touched

    (a / "frame_000001.json").unlink()
    third = make_dataset("cube", a, shake=0.5, seed=7, **KW)
    assert third["rendered"] == [1] and third["skipped"] == [0, 2]
    after = _files(a)
    for k in (0, 2):
        for e in ("exr", "png", "json"):
            assert after[f"frame_{k:06d}.{e}"] == before[f"frame_{k:06d}.{e}"]
    assert after["frame_000001.exr"][1] == before["frame_000001.exr"][1]  # same bits re-rendered

    make_dataset("cube", b, shake=0.5, seed=7, **KW)
    for k in range(3):
        for e in ("exr", "png", "json"):
            assert (a / f"frame_{k:06d}.{e}").read_bytes() == (b / f"frame_{k:06d}.{e}").read_bytes()


def test_bad_arguments_name_themselves_before_writing(tmp_path):
    cases = [
        (dict(frames=(3, 3)), "frames"),
        (dict(fps=0.0), "fps"),
        (dict(shutter_angle=400.0), "shutter_angle"),
        (dict(method="nope"), "method"),
        (dict(outputs=["blurred", "nope"]), "outputs"),
        (dict(outputs=["exposure"], method="accumulation"), "outputs"),
        (dict(shake=-1.0), "shake"),
        (dict(seed=-2), "seed"),
        (dict(width=0), "width"),
        (dict(method="accumulation", options={"nope": 1}), "options"),
        (dict(preview="webm"), "preview"),
        (dict(kernels=(0, 3)), "kernels"),
        (dict(kernels="4x3"), "kernels"),
        (dict(kernels=(4, 3), rolling=0.5, method="analytic"), "kernels"),
        (dict(error_estimate="no"), "error_estimate"),
    ]
    for kw, name in cases:
        with pytest.raises((ValueError, TypeError), match=name):
            make_dataset("cube", tmp_path / "x", **{**dict(progress=False), **kw})
    with pytest.raises(ValueError, match="scene_or_path"):
        make_dataset("no_such_scene", tmp_path / "x", progress=False)
    assert not (tmp_path / "x").exists()


@pytest.mark.parametrize("name", ["curved", "pan", "deforming_propeller", "bending_arm"])
def test_retimed_motion_equals_the_original_on_its_window(name):
    scene = mb.SCENES[name](width=32, height=24)
    motions = [o.motion for o in scene.objects if o.motion is not None]
    motions += [scene.camera_motion] if scene.camera_motion is not None else []
    assert motions
    rng = np.random.default_rng(1)
    for m in motions:
        for t0, t1 in [(0.0, 1.0), (0.2, 0.45), (1 / 3, 0.5), (0.9, 1.0)]:
            r = retime(m, t0, t1)
            for u in [0.0, 1.0, *rng.random(12)]:
                t = t0 + u * (t1 - t0)
                if m.is_deforming:
                    np.testing.assert_allclose(r.vertices_at(u), m.vertices_at(t), rtol=0, atol=1e-12)
                else:
                    np.testing.assert_allclose(r.transform_at(u), m.transform_at(t), rtol=0, atol=1e-12)


def test_a_gltf_file_two_frames(tmp_path):
    gl, blob = gw.animated_asset()
    path = gw.write(tmp_path, "glTF-Binary", gl, blob)
    run = make_dataset(path, tmp_path / "out", frames=(0, 2), fps=1.0, shutter_angle=90.0, method="accumulation",
                       options={"samples": 4}, width=48, height=32, progress=False)  # fmt: skip
    assert run["rendered"] == [0, 1]
    m1 = json.loads((tmp_path / "out" / "frame_000001.json").read_text())
    assert m1["shutter"]["window"] == pytest.approx([1.0, 1.25]) and m1["shutter"]["window_unit"] == "seconds"
    img0, img1 = (_arrays(tmp_path / "out", k)["rgba"] for k in (0, 1))
    assert img0.shape == (32, 48, 4) and not np.array_equal(img0, img1)


def test_the_command_line(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(Path(mb.__file__).parents[1])}
    cmd = [sys.executable, "-m", "motionblur", "dataset", "spinning_propeller", "--frames", "1:3", "--fps", "12",
           "--shutter-angle", "180", "--method", "accumulation", "--option", "samples=4", "--outputs",
           "blurred,flow,depth,ids", "--width", "40", "--height", "30", "--out", str(tmp_path / "cli")]  # fmt: skip
    done = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "2 frames rendered" in done.stdout
    meta = json.loads((tmp_path / "cli" / "frame_000002.json").read_text())
    assert meta["options"] == {"samples": 4} and meta["fps"] == 12.0
    bad = subprocess.run([*cmd[:5], "--frames", "3"], capture_output=True, text=True, env=env, timeout=120)
    assert bad.returncode != 0 and "--frames" in bad.stderr


def test_frames_without_their_error_estimate_are_the_same_frames(tmp_path):
    """``error_estimate=False`` (``--no-error-estimate``) skips the estimate, which for the
    analytic method is a second, finer render: each JSON holds None there, and the frames are the
    same bits as with it (the estimate only reads the frame)."""
    kw = dict(frames=(0, 2), width=48, height=36, method="analytic", progress=False, preview="none")
    make_dataset("curved", tmp_path / "with", **kw)
    run = make_dataset("curved", tmp_path / "without", error_estimate=False, **kw)
    assert run["error_estimate"] is False
    for k in (0, 1):
        with_ = json.loads((tmp_path / "with" / f"frame_{k:06d}.json").read_text())
        without = json.loads((tmp_path / "without" / f"frame_{k:06d}.json").read_text())
        assert with_["error_estimate"] > 0.0 and without["error_estimate"] is None
        for name, a in _arrays(tmp_path / "with", k).items():
            np.testing.assert_array_equal(a, _arrays(tmp_path / "without", k)[name], err_msg=name)
    env = {**os.environ, "PYTHONPATH": str(Path(mb.__file__).parents[1])}
    cmd = [sys.executable, "-m", "motionblur", "dataset", "curved", "--frames", "0:1", "--method", "analytic",
           "--width", "48", "--height", "36", "--preview", "none", "--no-progress", "--no-error-estimate",
           "--out", str(tmp_path / "cli")]  # fmt: skip
    done = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=120)
    assert done.returncode == 0, done.stderr
    assert json.loads((tmp_path / "cli" / "frame_000000.json").read_text())["error_estimate"] is None


@pytest.mark.dask
def test_frames_as_dask_tasks_equal_the_serial_run(tmp_path):
    import distributed

    kw = {**KW, "method": "analytic", "outputs": ["blurred", "sharp", "flow", "exposure"]}
    make_dataset("spinning_propeller", tmp_path / "serial", **kw)
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cl:
        with distributed.Client(cl, timeout=60) as client:
            assert len(client.scheduler_info()["workers"]) == 2
            run = make_dataset("spinning_propeller", tmp_path / "dask", client=client, **kw)
    assert run["rendered"] == [0, 1, 2]
    for k in range(3):
        a, b = _arrays(tmp_path / "serial", k), _arrays(tmp_path / "dask", k)
        assert a.keys() == b.keys() and any(n.startswith("extra.exposure.") for n in a)
        for n in a:
            np.testing.assert_array_equal(a[n], b[n], err_msg=n)


def test_one_frame_at_360_degrees_is_the_scene_itself(tmp_path):
    make_dataset("curved", tmp_path, frames=(0, 1), shutter_angle=360.0, method="accumulation",
                 options={"samples": 8}, width=64, height=48, progress=False)  # fmt: skip
    want = mb.render(mb.SCENES["curved"](width=64, height=48), "accumulation", samples=8).rgba
    np.testing.assert_allclose(_arrays(tmp_path, 0)["rgba"], want, rtol=0, atol=1e-5)


def test_a_failed_write_leaves_no_file_behind(tmp_path):
    from motionblur.dataset import _replace_into

    target = tmp_path / "frame_000000.exr"

    def half_then_fail(p):
        p.write_bytes(b"half")
        raise OSError("disk full")

    with pytest.raises(OSError, match="disk full"):
        _replace_into(target, half_then_fail)
    assert list(tmp_path.iterdir()) == []


def test_the_progress_bar_and_a_scene_object(tmp_path, capsys):
    scene = mb.SCENES["cube"](width=40, height=30)
    run = make_dataset(scene, tmp_path, frames=(2, 4), method="accumulation", options={"samples": 2})
    assert run["rendered"] == [2, 3] and run["width"] == 40
    assert "2/2" in capsys.readouterr().err
    m = json.loads((tmp_path / "frame_000003.json").read_text())
    assert m["shutter"]["window"] == pytest.approx([0.5, 0.75])


@pytest.mark.dask
def test_the_command_line_on_a_local_cluster(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(Path(mb.__file__).parents[1])}
    args = ["cube", "--frames", "0:2", "--method", "analytic", "--outputs", "blurred,flow", "--width", "40",
            "--height", "30", "--no-progress"]  # fmt: skip
    for extra in ([], ["--dask", "local"]):
        out = str(tmp_path / ("dask" if extra else "serial"))
        cmd = [sys.executable, "-m", "motionblur", "dataset", *args, "--out", out, *extra]
        done = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=120)
        assert done.returncode == 0, done.stderr
    for k in range(2):
        a, b = _arrays(tmp_path / "serial", k), _arrays(tmp_path / "dask", k)
        assert a.keys() == b.keys()
        for n in a:
            np.testing.assert_array_equal(a[n], b[n], err_msg=n)


def test_the_same_bytes_for_every_thread_count(tmp_path):
    old = mb.get_num_threads()
    try:
        for n in (1, 3):
            mb.set_num_threads(n)
            make_dataset("curved", tmp_path / str(n), frames=(0, 2), method="analytic", width=48, height=32,
                         outputs=["blurred", "sharp", "flow"], progress=False)  # fmt: skip
    finally:
        mb.set_num_threads(old)
    for k in range(2):
        for e in ("exr", "png", "json"):
            name = f"frame_{k:06d}.{e}"
            assert (tmp_path / "1" / name).read_bytes() == (tmp_path / "3" / name).read_bytes(), name


def test_a_rolling_shutter_reaches_every_frame(tmp_path):
    """--rolling: each frame's scene has the readout (the metadata says so), and the frame equals
    the analytic render of a rolling-shutter scene, which leans (differs from the global one)."""
    from motionblur.dataset import make_dataset

    kw = dict(frames=(0, 2), method="analytic", width=64, height=48, progress=False)
    make_dataset("cube", tmp_path / "r", rolling=0.5, **kw)
    make_dataset("cube", tmp_path / "g", **kw)
    meta = json.loads((tmp_path / "r" / "frame_000001.json").read_text())
    assert meta["rolling"] == 0.5
    rolled = mb.read_image(tmp_path / "r" / "frame_000001.exr").rgba
    still = mb.read_image(tmp_path / "g" / "frame_000001.exr").rgba
    assert np.abs(rolled - still).max() > 1e-3
    with pytest.raises(ValueError, match="rolling"):
        make_dataset("cube", tmp_path / "x", rolling=0.5, frames=(0, 1), method="velocity", progress=False)
    with pytest.raises(ValueError, match="rolling"):
        make_dataset("cube", tmp_path / "x", rolling=1.0, frames=(0, 1), progress=False)


def _decoded(path: Path) -> tuple[dict, list[np.ndarray]]:
    """The MP4 decoded by imageio-ffmpeg's ffmpeg: its metadata and every frame (8-bit RGB)."""
    import imageio_ffmpeg

    frames = imageio_ffmpeg.read_frames(str(path))
    meta = next(frames)
    w, h = meta["size"]
    return meta, [np.frombuffer(f, np.uint8).reshape(h, w, 3) for f in frames]


def _png_rgb(path: Path) -> np.ndarray:
    from PIL import Image

    with Image.open(path) as im:
        return np.asarray(im.convert("RGB"))


def test_an_mp4_preview_is_the_frames_the_same_bytes_twice_and_resumes(tmp_path):
    """preview='mp4': an H.264 file of every frame at fps, its odd size rounded up to even, whose
    decoded frames are the PNG previews (up to the codec's loss); the same command writes the
    same bytes; a rerun rewrites it only when a frame was rendered or it is missing."""
    kw = dict(frames=(0, 5), fps=10.0, method="analytic", width=63, height=47, progress=False, preview="mp4")
    a, b = tmp_path / "a", tmp_path / "b"
    run = make_dataset("cube", a, **kw)
    assert (
        run["preview"] == "preview.mp4"
        and json.loads((a / "dataset.json").read_text())["preview"] == "preview.mp4"
    )
    assert not (a / "preview.gif").exists() and not [p for p in a.iterdir() if ".tmp" in p.name]
    meta, frames = _decoded(a / "preview.mp4")
    assert meta["codec"] == "h264" and meta["fps"] == pytest.approx(10.0)
    assert meta["size"] == (64, 48) and len(frames) == 5
    for k, got in enumerate(frames):
        want = np.pad(_png_rgb(a / f"frame_{k:06d}.png"), ((0, 1), (0, 1), (0, 0)), mode="edge")
        err = np.abs(got.astype(float) - want).mean()
        assert err < 4.0, (k, err)  # 8-bit levels: crf 18 and 4:2:0 chroma lose little
    # the frames differ, and the video follows them (not one frame repeated)
    assert np.abs(frames[0].astype(float) - frames[4]).mean() > 4 * max(
        np.abs(
            f.astype(float)
            - np.pad(_png_rgb(a / f"frame_{k:06d}.png"), ((0, 1), (0, 1), (0, 0)), mode="edge")
        ).mean()
        for k, f in enumerate(frames)
    )

    make_dataset("cube", b, **kw)
    assert (a / "preview.mp4").read_bytes() == (b / "preview.mp4").read_bytes()

    before = _files(a)
    assert make_dataset("cube", a, **kw)["rendered"] == []
    assert _files(a) == before  # nothing re-encoded, not even touched
    (a / "frame_000002.json").unlink()
    assert make_dataset("cube", a, **kw)["rendered"] == [2]
    assert (a / "preview.mp4").read_bytes() == before["preview.mp4"][1]  # re-encoded, same bytes
    (a / "preview.mp4").unlink()
    assert make_dataset("cube", a, **kw)["rendered"] == []
    assert (a / "preview.mp4").read_bytes() == before["preview.mp4"][1]  # a missing preview is written

    none = make_dataset("cube", tmp_path / "none", **{**kw, "frames": (0, 1), "preview": "none"})
    assert none["preview"] is None and not [p for p in (tmp_path / "none").iterdir() if "preview" in p.name]


def _cli(tmp_path: Path, *args: str, block: str | None = None) -> subprocess.CompletedProcess:
    """``motionblur dataset ARGS`` in a new Python; ``block``: an import name made missing there
    the way Python reports one (``sys.modules[name] = None``: ``import name`` raises
    ModuleNotFoundError), before motionblur is imported."""
    env = {**os.environ, "PYTHONPATH": str(Path(mb.__file__).parents[1])}
    hide = f"sys.modules[{block!r}] = None; " if block else ""
    code = f"import sys; {hide}from motionblur.__main__ import main; sys.exit(main(sys.argv[1:]))"
    cmd = [sys.executable, "-c", code, "dataset", *args]
    return subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=180)


def test_the_command_line_writes_an_mp4_preview(tmp_path):
    out = tmp_path / "cli"
    done = _cli(tmp_path, "spinning_propeller", "--frames", "0:3", "--fps", "12", "--method", "analytic",
                "--width", "40", "--height", "30", "--no-progress", "--preview", "mp4", "--out", str(out))  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "3 frames rendered" in done.stdout
    meta, frames = _decoded(out / "preview.mp4")
    assert meta["size"] == (40, 30) and len(frames) == 3 and meta["fps"] == pytest.approx(12.0)
    assert not (out / "preview.gif").exists()
    bad = _cli(tmp_path, "cube", "--preview", "webm", "--out", str(tmp_path / "bad"))
    assert bad.returncode == 2 and "--preview" in bad.stderr and not (tmp_path / "bad").exists()


def test_an_mp4_preview_without_the_video_extra_names_it_before_writing(tmp_path):
    """imageio-ffmpeg missing: the command says which extra brings it and writes nothing (it
    does not fall back to a GIF); the default GIF preview does not need it."""
    out = tmp_path / "x"
    done = _cli(tmp_path, "cube", "--frames", "0:1", "--preview", "mp4", "--no-progress", "--out", str(out),
                block="imageio_ffmpeg")  # fmt: skip
    assert done.returncode == 1, (done.stdout, done.stderr)
    assert "motionblur[video]" in done.stderr and "imageio-ffmpeg" in done.stderr, done.stderr
    assert not out.exists()
    gif = _cli(tmp_path, "cube", "--frames", "0:1", "--method", "analytic", "--width", "32", "--height", "24",
               "--no-progress", "--out", str(tmp_path / "gif"), block="imageio_ffmpeg")  # fmt: skip
    assert gif.returncode == 0, gif.stderr
    assert (tmp_path / "gif" / "preview.gif").exists() and not (tmp_path / "gif" / "preview.mp4").exists()


def test_blur_kernels_per_frame_are_those_of_the_frames_scene(tmp_path):
    """kernels=(GX, GY): each frame's .npz holds blur_kernels of the scene the frame was rendered
    from (its window and its shake), the same bytes twice; the CLI's --kernels gives the same."""
    from motionblur.dataset import _frame_scene

    kw = dict(frames=(0, 2), method="analytic", width=64, height=48, shake=1.0, seed=3, progress=False)
    run = make_dataset("cube", tmp_path / "a", kernels=(4, 3), **kw)
    assert run["kernels"] == [4, 3]
    meta = json.loads((tmp_path / "a" / "frame_000001.json").read_text())
    assert meta["kernels"]["file"] == meta["files"]["kernels"] == "frame_000001_kernels.npz"
    got = np.load(tmp_path / "a" / "frame_000001_kernels.npz")
    assert got["points"].shape == (12, 2) and got["kernels"].shape[0] == 12
    assert got["kernels"].shape[1] == 2 * meta["kernels"]["radius"] + 1
    np.testing.assert_allclose(got["kernels"].sum(axis=(1, 2)) + got["clipped"], 1.0, atol=1e-5)
    # the same as blur_kernels of frame 1's own scene (window 1/2 .. 3/4 of the clip, its shake)
    job = {"source": ("builtin", "cube"), "window": (0.5, 0.75), "width": 64, "height": 48, "fps": 24.0,
           "shutter_angle": 180.0, "shake": 1.0, "shake_seed": meta["shake_seed"]}  # fmt: skip
    want = mb.blur_kernels(_frame_scene(job), grid=(4, 3))
    np.testing.assert_array_equal(got["kernels"], want.kernels)
    np.testing.assert_array_equal(got["ids"], want.ids)
    assert (got["ids"] >= 0).any(), "the grid sees the cube"
    # the shake is in them: without it, the kernels differ
    still = make_dataset("cube", tmp_path / "still", kernels=(4, 3), **{**kw, "shake": None})
    assert still["rendered"] == [0, 1]
    k0 = np.load(tmp_path / "still" / "frame_000001_kernels.npz")["paths"]
    assert not np.allclose(k0, got["paths"], equal_nan=True)

    done = _cli(tmp_path, "cube", "--frames", "0:2", "--method", "analytic", "--width", "64", "--height", "48",
                "--shake", "1", "--seed", "3", "--kernels", "4x3", "--no-progress", "--out", str(tmp_path / "cli"))  # fmt: skip
    assert done.returncode == 0, done.stderr
    for k in range(2):
        name = f"frame_{k:06d}_kernels.npz"
        assert (tmp_path / "cli" / name).read_bytes() == (tmp_path / "a" / name).read_bytes(), name
    bad = _cli(tmp_path, "cube", "--kernels", "4by3", "--out", str(tmp_path / "bad"))
    assert bad.returncode == 2 and "--kernels" in bad.stderr and not (tmp_path / "bad").exists()
