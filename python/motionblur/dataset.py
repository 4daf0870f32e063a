"""Frame sequences for training and testing: ``make_dataset`` (and ``motionblur dataset``).

A clip is a scene's motion cut into frames at ``fps`` with a shutter ``angle``: frame k is
exposed for ``(angle / 360) / fps`` seconds from its start. For a glTF file, frame k's shutter
spans seconds ``[k / fps, k / fps + (angle / 360) / fps]`` of the file's animation. A built-in
scene is defined over the shutter [0, 1] only: frames ``A:B`` treat that [0, 1] as the whole clip
of ``N = B - A`` frames, frame k exposing ``[(k - A) / N, (k - A) / N + (angle / 360) / N]`` of
it; its motions are re-timed to that window exactly ([`retime`][motionblur.dataset.retime]).

Every frame gives ``frame_KKKKKK.exr`` (every channel by name: ``R G B A`` the blurred frame,
``Z`` depth, ``id`` object ids, ``velocity.X/Y``, and the ground-truth outputs asked for),
``frame_KKKKKK.png`` (an 8-bit preview) and ``frame_KKKKKK.json`` (camera, shutter, method,
options, error estimate, seed, library version), with ``kernels=(GX, GY)`` also
``frame_KKKKKK_kernels.npz`` (the blur's point-spread functions at a GX x GY grid of pixels,
[`blur_kernels`][motionblur.shake.blur_kernels]); ``dataset.json`` describes the run and a
preview shows the sequence: ``preview.gif`` (the default), ``preview.mp4`` (H.264 through the
ffmpeg that ``motionblur[video]`` installs, encoded on one thread with bit-exact muxing, so the
same frames give the same file) or none. Each file is written under a temporary name in the same
folder and renamed into place, the JSON last: a frame whose JSON exists is done and a rerun skips
it; no half-written file is ever left under a final name. The same command gives the same bits
(nothing timed goes into the files).
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .scene import Motion, Object, Scene

__all__ = ["make_dataset", "retime", "frame_window", "OUTPUT_NAMES", "PREVIEWS"]

#: The ``outputs`` a dataset can hold: ``blurred``, ``depth`` and ``ids`` are the frame's own
#: buffers (always in the EXR); the others are [`render`][motionblur.render.render]'s ground truth.
OUTPUT_NAMES = ("blurred", "depth", "ids", "sharp", "flow", "exposure", "trajectory")
_BASE = {"blurred", "depth", "ids"}
#: The ``preview`` a dataset can have: ``gif`` (Pillow), ``mp4`` (``motionblur[video]``) or ``none``.
PREVIEWS = ("gif", "mp4", "none")


# ---------------------------------------------------------------- re-timing


def retime(motion: Motion, t0: float, t1: float) -> Motion:
    """The part of ``motion`` over shutter times ``[t0, t1]`` (0 <= t0 < t1 <= 1), stretched
    over [0, 1]: its value at u equals ``motion``'s at ``t0 + u (t1 - t0)``. Keys at both ends
    (``transform_at`` / ``vertices_at``) and the original keys strictly inside: keyframes
    interpolate piecewise (lerp, slerp, lerp), so this reproduces the motion exactly."""
    t0, t1 = float(t0), float(t1)
    if not (0.0 <= t0 < t1 <= 1.0):
        raise ValueError(f"window: expected 0 <= t0 < t1 <= 1, got ({t0!r}, {t1!r})")
    inside = [float(t) for t in motion.times if t0 < t < t1]
    times = [t0, *inside, t1]
    u = np.array([(t - t0) / (t1 - t0) for t in times])
    u[0], u[-1] = 0.0, 1.0
    if motion.is_deforming:
        return Motion.deforming(u, np.stack([motion.vertices_at(t) for t in times]))
    return Motion(u, np.stack([motion.transform_at(t) for t in times]))


def _retime_scene(scene: Scene, t0: float, t1: float, camera_motion) -> Scene:
    objects = []
    for o in scene.objects:
        m = None if o.motion is None else retime(o.motion, t0, t1)
        objects.append(Object(o.mesh, o.color, shading=o.shading, motion=m, name=o.name))
    return scene.with_(objects=objects, camera_motion=camera_motion)


def _compose(outer: Motion | None, inner: Motion) -> Motion:
    """``outer(t) @ inner(t)`` sampled at the union of both keys (``inner`` alone when no outer)."""
    if outer is None:
        return inner
    times = np.union1d(outer.times, inner.times)
    return Motion(times, outer.transforms_at(times) @ inner.transforms_at(times))


def frame_window(k: int, frames: tuple[int, int], fps: float, shutter_angle: float, builtin: bool):
    """Frame ``k``'s shutter: (t0, t1) in the built-in scene's [0, 1] (``builtin``) or in
    seconds of a glTF animation."""
    a, b = frames
    open_fraction = shutter_angle / 360.0
    if builtin:
        n = b - a
        t0 = (k - a) / n
        return t0, min(1.0, t0 + open_fraction / n)
    return k / fps, k / fps + open_fraction / fps


def _shake_seed(seed: int, k: int) -> int:
    return int(np.random.SeedSequence([int(seed), int(k)]).generate_state(1)[0])


# ---------------------------------------------------------------- one frame


def _source_scene(source, width: int, height: int, window) -> Scene:
    """The scene a frame is cut from (built per frame: no module-level store, and a built-in
    scene costs milliseconds against a frame's render)."""
    kind, value = source
    if kind == "gltf":
        return Scene.from_gltf(value, shutter=window, width=width, height=height)
    if kind == "builtin":
        from .scenes_builtin import SCENES

        return SCENES[value](width=width, height=height)
    return value


def _frame_scene(job: dict) -> Scene:
    source = job["source"]
    window = job["window"]
    builtin = source[0] != "gltf"
    scene = _source_scene(source, job["width"], job["height"], window)
    camera_motion = None
    if builtin:
        cm = scene.camera_motion
        camera_motion = None if cm is None else retime(cm, *window)
    else:
        camera_motion = scene.camera_motion
    if job["shake"] is not None:
        from .shake import camera_shake

        exposure = (job["shutter_angle"] / 360.0) / job["fps"]
        shake = camera_shake(
            scene.camera.pose, exposure=exposure, intensity=job["shake"], seed=job["shake_seed"]
        )
        camera_motion = _compose(camera_motion, shake)
    rolling = job.get("rolling", 0.0)
    if builtin:
        scene = _retime_scene(scene, *window, camera_motion)
        return scene.with_(rolling=rolling) if rolling else scene
    return scene.with_(camera_motion=camera_motion, rolling=rolling)


def _untimed(x):
    """``x`` without what varies from run to run: timings (keys ``ms``, ``ms_*``, ``*_ms``,
    ``*seconds``) and the static-layer cache's state (``static_*``, which depends on what the
    process rendered before): files stay bit-stable."""
    if isinstance(x, dict):
        return {k: _untimed(v) for k, v in x.items() if not _varies(str(k))}
    if isinstance(x, (list, tuple)):
        return [_untimed(v) for v in x]
    return x


def _varies(key: str) -> bool:
    return key == "ms" or key.startswith(("ms_", "static_")) or key.endswith(("_ms", "seconds"))


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, (float, int, str, bool)) or x is None:
        return x
    return str(x)


def _replace_into(path: Path, write) -> None:
    """``write(tmp)`` then rename ``tmp`` to ``path`` (same folder: the rename is atomic)."""
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp{path.suffix}")
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def _write_json(path: Path, data: dict) -> None:
    text = json.dumps(_jsonable(data), indent=2, sort_keys=True) + "\n"
    if path.exists() and path.read_text() == text:
        return  # a rerun rewrites nothing
    _replace_into(path, lambda p: p.write_text(text))


def _stem(k: int) -> str:
    return f"frame_{k:06d}"


def _write_kernels(scene: Scene, grid, path: Path) -> dict:
    """The frame's blur kernels at a ``grid`` (GX, GY) of pixels into ``path`` (.npz: ``points``,
    ``kernels``, ``paths``, ``times``, ``weights``, ``clipped``, ``ids``, as in
    [`BlurKernels`][motionblur.shake.BlurKernels]); returns what the frame's JSON says of them."""
    from .shake import blur_kernels

    bk = blur_kernels(scene, grid=tuple(grid))
    arrays = {n: getattr(bk, n) for n in ("points", "kernels", "paths", "times", "weights", "clipped", "ids")}
    # deflated (a kernel image is mostly zeros, so this is hundreds of times smaller); the zip
    # entries carry no time, so the same kernels give the same bytes
    _replace_into(path, lambda p: np.savez_compressed(p, **arrays))
    return {"file": path.name, "grid": list(grid), "radius": (bk.kernels.shape[1] - 1) // 2}


def render_frame(job: dict) -> dict:
    """Render and write one frame of a dataset (a task: ``job`` is plain data) and return its
    metadata. Skips the frame (returning the metadata on disk) when its JSON exists."""
    from . import __version__
    from .render import render

    out, k = Path(job["out"]), job["k"]
    meta_path = out / f"{_stem(k)}.json"
    if meta_path.exists():
        return {**json.loads(meta_path.read_text()), "skipped": True}
    scene = _frame_scene(job)
    gt = [n for n in job["outputs"] if n not in _BASE]
    frame = render(
        scene, job["method"], outputs=gt, error_estimate=job.get("error_estimate", True), **job["options"]
    )
    frame.stats = _untimed(frame.stats)
    _replace_into(out / f"{_stem(k)}.exr", frame.save_exr)
    _replace_into(out / f"{_stem(k)}.png", frame.save_png)
    files = {"exr": f"{_stem(k)}.exr", "png": f"{_stem(k)}.png"}
    kernels = None
    if job.get("kernels"):
        kernels = _write_kernels(scene, job["kernels"], out / f"{_stem(k)}_kernels.npz")
        files["kernels"] = kernels["file"]
    cam = scene.camera
    meta = {
        "frame": k,
        "library_version": __version__,
        "scene": job["scene_name"],
        "width": frame.width,
        "height": frame.height,
        "fps": job["fps"],
        "shutter_angle": job["shutter_angle"],
        "shutter": {
            "window": list(job["window"]),
            "window_unit": "seconds" if job["source"][0] == "gltf" else "scene shutter [0, 1]",
            "open_seconds": k / job["fps"],
            "exposure_seconds": (job["shutter_angle"] / 360.0) / job["fps"],
        },
        "camera": {
            "pose": cam.pose,
            "intrinsics": {
                a: getattr(cam, a) for a in ("width", "height", "yfov", "znear", "zfar") if hasattr(cam, a)
            },
            "pose_at_open": scene.camera_pose_at(0.0),
            "pose_at_close": scene.camera_pose_at(1.0),
        },
        "method": job["method"],
        "plan": frame.stats.get("plan", {}).get("kept"),  # what auto chose
        "options": job["options"],
        "outputs": list(job["outputs"]),
        "error_estimate": frame.stats.get("error_estimate"),
        "seed": job["seed"],
        "shake": job["shake"],
        "shake_seed": job["shake_seed"],
        "rolling": job.get("rolling", 0.0),
        "kernels": kernels,
        "files": files,
    }
    _write_json(meta_path, meta)  # last: the frame is done
    return {**meta, "skipped": False}


# ---------------------------------------------------------------- the run


def _source_of(scene_or_path) -> tuple[tuple[str, Any], str]:
    from .scenes_builtin import SCENES

    if isinstance(scene_or_path, Scene):
        return ("scene", scene_or_path), "Scene"
    if isinstance(scene_or_path, (str, os.PathLike)):
        text = os.fspath(scene_or_path)
        if text in SCENES:
            return ("builtin", text), text
        if text.lower().endswith((".glb", ".gltf")):
            if not Path(text).is_file():
                raise FileNotFoundError(f"scene_or_path: no such file {text!r}")
            return ("gltf", str(Path(text).resolve())), Path(text).name
        raise ValueError(
            f"scene_or_path: expected a .glb/.gltf file or a built-in scene ({', '.join(sorted(SCENES))}), got {text!r}"
        )
    raise TypeError(
        f"scene_or_path: expected a Scene, a path or a scene name, got {type(scene_or_path).__name__}"
    )


def _check_kernels(kernels, rolling) -> None:
    if kernels is None:
        return
    if (
        isinstance(kernels, str)
        or not isinstance(kernels, Sequence)
        or len(kernels) != 2
        or not all(
            isinstance(g, (int, np.integer)) and not isinstance(g, bool) and 1 <= g <= 1024 for g in kernels
        )
    ):
        raise ValueError(
            f"kernels: expected None or a grid (GX, GY) of integers in [1, 1024], got {kernels!r}"
        )
    if rolling > 0.0:
        raise ValueError(
            "kernels: blur kernels follow a global shutter; they cannot be given with rolling > 0"
        )


def _check(frames, fps, shutter_angle, method, options, outputs, shake, seed, width, height, rolling=0.0):
    from .render import METHODS, ROLLING_METHODS

    if isinstance(rolling, bool) or not isinstance(rolling, (int, float)) or not 0.0 <= rolling < 1.0:
        raise ValueError(f"rolling: expected a readout in [0, 1), got {rolling!r}")
    if rolling > 0.0 and method not in ROLLING_METHODS:
        raise ValueError(
            f"rolling: method {method!r} cannot model a rolling shutter; use one of {', '.join(sorted(ROLLING_METHODS))}"
        )

    if (
        not isinstance(frames, Sequence)
        or len(frames) != 2
        or not all(isinstance(f, (int, np.integer)) and not isinstance(f, bool) for f in frames)
        or not 0 <= frames[0] < frames[1]
    ):
        raise ValueError(f"frames: expected (A, B) integers with 0 <= A < B, got {frames!r}")
    for name, v in (("fps", fps), ("shutter_angle", shutter_angle)):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v):
            raise ValueError(f"{name}: expected a finite number, got {v!r}")
    if not fps > 0:
        raise ValueError(f"fps: must be > 0, got {fps!r}")
    if not 0 < shutter_angle <= 360:
        raise ValueError(f"shutter_angle: must be in (0, 360] degrees, got {shutter_angle!r}")
    if not isinstance(method, str) or method not in METHODS:
        raise ValueError(f"method: unknown method {method!r}; expected one of {', '.join(sorted(METHODS))}")
    if options is not None and not isinstance(options, dict):
        raise TypeError(f"options: expected a dict of the method's options, got {type(options).__name__}")
    if isinstance(outputs, str) or not all(isinstance(n, str) for n in outputs):
        raise TypeError("outputs: expected a list of names such as ['blurred', 'flow']")
    bad = [n for n in outputs if n not in OUTPUT_NAMES]
    if bad:
        raise ValueError(
            f"outputs: unknown {', '.join(map(repr, bad))}; expected some of {', '.join(OUTPUT_NAMES)}"
        )
    if "exposure" in outputs and method != "analytic":
        raise ValueError(f"outputs: 'exposure' is given by method 'analytic' only, not by {method!r}")
    if shake is not None and (
        isinstance(shake, bool) or not isinstance(shake, (int, float)) or not shake >= 0
    ):
        raise ValueError(f"shake: expected None or an intensity >= 0, got {shake!r}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed: expected an integer >= 0, got {seed!r}")
    from ._core import MAX_PIXELS

    for name, v in (("width", width), ("height", height)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not v >= 1:
            raise ValueError(f"{name}: expected an integer >= 1 pixels, got {v!r}")
    if width * height > MAX_PIXELS:
        raise ValueError(f"width: width x height must be at most {MAX_PIXELS} pixels, got {width}x{height}")


def make_dataset(
    scene_or_path,
    out,
    *,
    frames: tuple[int, int] = (0, 8),
    fps: float = 24.0,
    shutter_angle: float = 180.0,
    method: str = "auto",
    options: dict | None = None,
    outputs: Sequence[str] = ("blurred",),
    shake: float | None = None,
    seed: int = 0,
    rolling: float = 0.0,
    width: int = 320,
    height: int = 240,
    client=None,
    progress: bool = True,
    preview: str = "gif",
    kernels: tuple[int, int] | None = None,
    error_estimate: bool = True,
) -> dict:
    """Render frames ``A:B`` of a clip into the folder ``out`` (see the module's text for the
    files and how a frame's shutter is placed in the clip).

    ``scene_or_path``: a glTF 2.0 file (``.glb``/``.gltf``, its animation in seconds; needs
    ``motionblur[interop]``), a built-in scene's name (``motionblur.SCENES``, whose shutter [0, 1]
    is the whole clip) or a [`Scene`][motionblur.scene.Scene] (treated as a built-in one; ``width``
    and ``height`` are then its camera's). ``out``: the folder (created). ``frames``: ``(A, B)``,
    frames A to B - 1, 0 <= A < B. ``fps``: frames per second, > 0. ``shutter_angle``: degrees in
    (0, 360]; each frame is exposed ``(shutter_angle / 360) / fps`` seconds. ``method``: a
    rendering method ([`render`][motionblur.render.render]); ``options``: its options (dict).
    ``outputs``: names among ``OUTPUT_NAMES``: ``blurred``, ``depth``, ``ids`` (always in the
    EXR), ``sharp``, ``flow``, ``trajectory``, ``exposure`` (ground truth at the shutter's open,
    centre and close; ``exposure`` needs ``method="analytic"``). ``shake``: None or a hand-held
    camera shake's intensity >= 0 ([`camera_shake`][motionblur.shake.camera_shake]), seeded per frame from
    ``seed`` (an integer >= 0) and the frame number. ``rolling``: a rolling shutter's readout in
    [0, 1) of each frame's exposure, rows read top to bottom (``Scene(rolling=...)``; 0 a global
    shutter; the methods of ``motionblur.render.ROLLING_METHODS`` only). ``width``, ``height``: pixels.
    ``client``: None (frames rendered here, one after another) or a ``dask.distributed.Client``
    (frames as tasks; its workers must see ``out``). ``progress``: a tqdm bar on stderr (needs tqdm).
    ``preview``: the sequence's preview, one of ``PREVIEWS``: ``"gif"`` (``preview.gif``, Pillow),
    ``"mp4"`` (``preview.mp4``, H.264 in yuv420p at ``fps``, its size rounded up to even pixels by
    repeating the last row/column; needs ``motionblur[video]``, else MissingDependencyError naming
    it before anything is written) or ``"none"``. A rerun that renders nothing rewrites no preview
    that exists. ``kernels``: None, or a grid ``(GX, GY)`` of evenly spread pixels (integers in
    [1, 1024]) at which each frame's blur kernels are written (``frame_KKKKKK_kernels.npz``: the
    point-spread function of the surface seen at each pixel at the frame's reference time, from
    its exact screen path over the shutter, its radius the smallest that holds every path;
    [`blur_kernels`][motionblur.shake.blur_kernels]); not with ``rolling`` > 0, and a frame
    where a deforming object is seen at a grid pixel raises its ValueError. ``error_estimate``:
    each frame's estimated RMSE against the exact time integral in its JSON (True, the default;
    the analytic method measures it against a second, finer render, about twice the frame's time
    up to 1080p, and from a 1080p pilot above, about 0.8x a 4K frame's time) or None there
    (False: ``render(..., error_estimate=False)``).

    Returns the run's metadata (also in ``out/dataset.json``) with ``rendered`` and ``skipped``,
    the frame numbers rendered now and those already on disk. Bad arguments raise ValueError or
    TypeError naming the argument before anything is written.
    """
    from . import __version__

    source, scene_name = _source_of(scene_or_path)
    options = dict(options or {})
    outputs = list(dict.fromkeys(outputs))
    _check(frames, fps, shutter_angle, method, options, outputs, shake, seed, width, height, rolling)
    _check_kernels(kernels, rolling)
    if not isinstance(error_estimate, bool):
        raise TypeError(f"error_estimate: expected True or False, got {type(error_estimate).__name__}")
    from .render import METHODS, _unknown_options

    bad = _unknown_options(METHODS[method], options)
    if bad:
        raise TypeError(f"options: method {method!r} has no option {', '.join(map(repr, bad))}")
    if not isinstance(preview, str) or preview not in PREVIEWS:
        raise ValueError(f"preview: expected one of {', '.join(map(repr, PREVIEWS))}, got {preview!r}")
    _require_preview(preview)
    if source[0] == "scene":
        width, height = source[1].camera.width, source[1].camera.height
    a, b = int(frames[0]), int(frames[1])
    fps, shutter_angle = float(fps), float(shutter_angle)
    tqdm = None
    if progress:
        from ._optional import require

        tqdm = require("tqdm", "the progress bar of motionblur dataset (progress=False goes without)").tqdm
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    jobs = [
        {
            "out": str(out),
            "k": k,
            "source": source,
            "scene_name": scene_name,
            "window": frame_window(k, (a, b), fps, shutter_angle, source[0] != "gltf"),
            "width": int(width),
            "height": int(height),
            "fps": fps,
            "shutter_angle": shutter_angle,
            "method": method,
            "options": options,
            "outputs": outputs,
            "shake": None if shake is None else float(shake),
            "seed": int(seed),
            "shake_seed": None if shake is None else _shake_seed(seed, k),
            "rolling": float(rolling),
            "kernels": None if kernels is None else [int(g) for g in kernels],
            "error_estimate": error_estimate,
        }
        for k in range(a, b)
    ]
    bar = tqdm(total=len(jobs), desc="motionblur dataset", unit="frame") if tqdm else None
    metas = _run_jobs(jobs, client, bar)
    run = {
        "library_version": __version__,
        "scene": scene_name,
        "frames": [a, b],
        "fps": fps,
        "shutter_angle": shutter_angle,
        "exposure_seconds": (shutter_angle / 360.0) / fps,
        "method": method,
        "options": options,
        "outputs": outputs,
        "shake": shake,
        "seed": int(seed),
        "rolling": float(rolling),
        "kernels": None if kernels is None else [int(g) for g in kernels],
        "width": int(width),
        "height": int(height),
        "frame_files": [f"{_stem(k)}.json" for k in range(a, b)],
        "preview": None if preview == "none" else f"preview.{preview}",
        "error_estimate": error_estimate,
    }
    _write_json(out / "dataset.json", run)
    if run["preview"] and (any(not m["skipped"] for m in metas) or not (out / run["preview"]).exists()):
        (_write_gif if preview == "gif" else _write_mp4)(out, range(a, b), fps)
    return {
        **run,
        "rendered": [m["frame"] for m in metas if not m["skipped"]],
        "skipped": [m["frame"] for m in metas if m["skipped"]],
    }


def _run_jobs(jobs: list[dict], client, bar) -> list[dict]:
    """Every frame's metadata, rendered here one after another (``client`` None) or as Dask
    tasks, in frame order; ``bar`` (a tqdm bar or None) counts the frames done and is closed."""
    metas = []
    if client is None:
        for job in jobs:
            metas.append(render_frame(job))
            if bar:
                bar.update(1)
    else:
        distributed = __import__("distributed")
        futures = client.map(render_frame, jobs, pure=False)
        for fut in distributed.as_completed(futures):
            fut.result()
            if bar:
                bar.update(1)
        metas = client.gather(futures)
    if bar:
        bar.close()
    return metas


def _require_preview(preview: str) -> None:
    """Raise MissingDependencyError, naming the extra, when ``preview`` needs a package that is
    not installed (before anything is written)."""
    from ._optional import require

    if preview in ("gif", "mp4"):
        require("PIL", f"the dataset's {preview.upper()} preview (preview={preview!r})")
    if preview == "mp4":
        require("imageio_ffmpeg", "the dataset's MP4 preview (preview='mp4', --preview mp4)")


def _write_gif(out: Path, ks, fps: float) -> None:
    """``preview.gif`` of the frames' PNG previews (Pillow), at ``fps``."""
    from PIL import Image as image

    pics = []
    for k in ks:
        with image.open(out / f"{_stem(k)}.png") as im:
            pics.append(im.convert("RGB").convert("P", palette=image.Palette.ADAPTIVE))
    ms = max(20, int(round(1000.0 / fps)))

    def write(p):
        pics[0].save(p, save_all=True, append_images=pics[1:], duration=ms, loop=0)

    _replace_into(out / "preview.gif", write)


#: ffmpeg's output options for ``preview.mp4``: H.264 (x264, fixed preset and quality) in yuv420p
#: for every player; one thread and bit-exact muxing (no encoder version string, no creation time,
#: no metadata), so the same frames give the same bytes.
_MP4_OPTIONS = (
    "-an", "-c:v", "libx264", "-preset", "medium", "-crf", "18", "-pix_fmt", "yuv420p",
    "-threads", "1", "-fflags", "+bitexact", "-flags:v", "+bitexact", "-map_metadata", "-1",
    "-movflags", "+faststart",
)  # fmt: skip


def _even_rgb(path: Path) -> np.ndarray:
    """The PNG at ``path`` as 8-bit RGB, padded to even width and height by repeating the last
    column/row (yuv420p halves the chroma both ways)."""
    from PIL import Image as image

    with image.open(path) as im:
        rgb = np.asarray(im.convert("RGB"))
    h, w = rgb.shape[:2]
    return np.ascontiguousarray(np.pad(rgb, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge"))


def _write_mp4(out: Path, ks, fps: float) -> None:
    """``preview.mp4`` of the frames' PNG previews at ``fps``: the frames are piped to the ffmpeg
    that imageio-ffmpeg ships (``_MP4_OPTIONS``); RuntimeError with ffmpeg's message if it fails."""
    import subprocess
    import tempfile
    from fractions import Fraction

    import imageio_ffmpeg

    ks = list(ks)
    first = _even_rgb(out / f"{_stem(ks[0])}.png")
    h, w = first.shape[:2]
    rate = Fraction(fps).limit_denominator(1001)

    def write(p):
        cmd = [imageio_ffmpeg.get_ffmpeg_exe(), "-nostdin", "-y", "-v", "error", "-f", "rawvideo",
               "-pix_fmt", "rgb24", "-s", f"{w}x{h}", "-r", str(rate), "-i", "-", *_MP4_OPTIONS,
               "-f", "mp4", str(p)]  # fmt: skip
        with tempfile.TemporaryFile() as log:
            proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=log)
            try:
                for i, k in enumerate(ks):
                    proc.stdin.write((first if i == 0 else _even_rgb(out / f"{_stem(k)}.png")).tobytes())
            except BrokenPipeError:
                pass  # ffmpeg stopped: its return code and message say why
            finally:
                proc.stdin.close()
                code = proc.wait()
            if code != 0:
                log.seek(0)
                message = log.read().decode(errors="replace").strip()
                raise RuntimeError(f"ffmpeg could not write the MP4 preview (exit {code}): {message}")

    _replace_into(out / "preview.mp4", write)


from ._namespace import tidy  # noqa: E402  (dir() lists the API only; see motionblur._namespace)

tidy(__name__)
