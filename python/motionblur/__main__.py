"""Command line: ``motionblur render FILE --method NAME --out IMAGE``, ``motionblur demo [--out DIR]``,
``motionblur dataset SCENE --out DIR``, ``motionblur bench [options]`` and ``motionblur --version`` (also ``python -m motionblur ...``; pip
installs the ``motionblur`` script)."""

from __future__ import annotations

import argparse
import ast
import sys


def main(argv: list[str] | None = None) -> int:
    from ._core import __version__
    from ._optional import MissingDependencyError

    parser = argparse.ArgumentParser(prog="motionblur")
    parser.add_argument("--version", action="version", version=f"motionblur {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser(
        "demo",
        help="a small speed-against-error run on three scenes with every method: images and a table (under a minute)",
    )
    demo.add_argument("--out", default="out/demo")
    _render_parser(sub)
    _dataset_parser(sub)
    sub.add_parser(
        "bench", help="the speed-against-error report (python -m motionblur bench --help)", add_help=False
    )
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        if argv[:1] == ["bench"]:
            from .evaluation.bench import main as bench_main

            return bench_main(argv[1:])
        args = parser.parse_args(argv)
        if args.command == "demo":
            from .evaluation.demo import run

            return run(args.out)
        if args.command == "render":
            return _render(args)
        if args.command == "dataset":
            return _dataset(args)
    except MissingDependencyError as exc:  # a clear line, not a traceback: what to install
        print(f"motionblur: {exc}", file=sys.stderr)
        return 1
    return 2


def _render_parser(sub) -> None:
    render = sub.add_parser(
        "render",
        help="render a glTF 2.0 file (.glb or .gltf, its animation over the shutter) to a PNG or EXR",
        description="Render the glTF 2.0 FILE with one method and write the frame to --out (.png: 8-bit "
        "sRGB; .exr: every buffer, linear float). The shutter spans the file's animation unless "
        "--shutter says which seconds; the camera is the file's first, else one framing the scene.",
    )
    render.add_argument("file", help="a glTF 2.0 file: .glb, or .gltf with its buffers")
    render.add_argument("--method", default="auto", help="a rendering method (default auto): accumulation, analytic, "
                        "motion_volume, velocity, opaque_image, camera_velocity, blur_shell, auto, or one registered "
                        "with motionblur.register")  # fmt: skip
    render.add_argument("--out", required=True, help="the image to write: a name ending in .png or .exr")
    render.add_argument("--width", type=int, default=640, help="pixels (default 640)")
    render.add_argument("--height", type=int, default=480, help="pixels (default 480)")
    render.add_argument("--shutter", type=float, nargs=2, metavar=("START", "END"),
                        help="seconds of the animation the shutter spans (default: all of it)")  # fmt: skip
    render.add_argument("--tolerance", type=float,
                        help="auto: the RMSE the frame's error estimate must meet (default 0.01)")  # fmt: skip
    render.add_argument("--samples", type=int, help="accumulation: the time samples")
    render.add_argument("--option", action="append", default=[], metavar="NAME=VALUE",
                        help="any other option of the method, e.g. --option aa=2 (repeatable; help(motionblur.render))")  # fmt: skip


def _dataset_parser(sub) -> None:
    d = sub.add_parser(
        "dataset",
        help="render frames of a clip (glTF file or built-in scene) to EXR + PNG + JSON, resumable",
        description="Render frames A:B of SCENE (a .glb/.gltf file, its animation in seconds, or a "
        "built-in scene whose shutter [0, 1] is the whole clip) into --out: per frame an EXR with every "
        "channel by name, a PNG preview and a JSON of metadata; dataset.json and a preview of the sequence "
        "(--preview: gif, mp4 or none) for the run. "
        "Frames already written are skipped; the same command gives the same bits.",
    )
    d.add_argument("scene", help="a .glb/.gltf file or a built-in scene name (motionblur.SCENES)")
    d.add_argument("--frames", default="0:8", help="A:B, frames A to B-1 (default 0:8)")
    d.add_argument("--fps", type=float, default=24.0, help="frames per second (default 24)")
    d.add_argument("--shutter-angle", type=float, default=180.0, help="degrees in (0, 360] (default 180)")
    d.add_argument("--shake", type=float, help="hand-held camera shake intensity (default none)")
    d.add_argument("--seed", type=int, default=0, help="seed of the shake (default 0)")
    d.add_argument("--rolling", type=float, default=0.0,
                   help="rolling shutter readout in [0, 1) of the exposure, rows top to bottom (default 0: global)")  # fmt: skip
    d.add_argument("--method", default="auto", help="a rendering method (default auto)")
    d.add_argument("--option", action="append", default=[], metavar="NAME=VALUE",
                   help="an option of the method, e.g. --option aa=2 (repeatable)")  # fmt: skip
    d.add_argument("--outputs", default="blurred",
                   help="comma-separated: blurred,sharp,exposure,flow,depth,ids,trajectory (default blurred)")  # fmt: skip
    d.add_argument("--kernels", metavar="GXxGY",
                   help="also write each frame's blur kernels at a GX x GY grid of pixels (e.g. 8x6) to frame_KKKKKK_kernels.npz")  # fmt: skip
    d.add_argument("--width", type=int, default=320, help="pixels (default 320)")
    d.add_argument("--height", type=int, default=240, help="pixels (default 240)")
    d.add_argument("--out", required=True, help="the folder to write")
    d.add_argument("--dask", metavar="local|ADDRESS",
                   help="render frames as Dask tasks: 'local' (a LocalCluster) or a scheduler's address")  # fmt: skip
    d.add_argument("--no-progress", action="store_true", help="no progress bar")
    d.add_argument(
        "--no-error-estimate",
        action="store_true",
        help="no error estimate in each frame's JSON (the analytic method's costs about "
        "twice the frame's time)",
    )
    d.add_argument("--preview", choices=("gif", "mp4", "none"), default="gif",
                   help="the sequence's preview: preview.gif (default), preview.mp4 (H.264; needs "
                   "motionblur[video]) or none")  # fmt: skip


def _parse_options(items: list[str], command: str) -> dict | None:
    options = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            print(f"motionblur {command}: --option: expected NAME=VALUE, got {item!r}", file=sys.stderr)
            return None
        options[name.strip()] = _option_value(value.strip())
    return options


def _dataset(args) -> int:
    from .dataset import make_dataset

    options = _parse_options(args.option, "dataset")
    if options is None:
        return 2
    a, sep, b = args.frames.partition(":")
    try:
        frames = (int(a), int(b))
    except ValueError:
        frames = None
    if not sep or frames is None:
        print(f"motionblur dataset: --frames: expected A:B, got {args.frames!r}", file=sys.stderr)
        return 2
    kernels = None
    if args.kernels is not None:
        gx, sep, gy = args.kernels.lower().partition("x")
        try:
            kernels = (int(gx), int(gy))
        except ValueError:
            sep = ""
        if not sep:
            print(
                f"motionblur dataset: --kernels: expected GXxGY such as 8x6, got {args.kernels!r}",
                file=sys.stderr,
            )
            return 2
    client = None
    try:
        if args.dask:
            from .evaluation.cluster import client_for

            client = client_for(args.dask)
        run = make_dataset(
            args.scene, args.out, frames=frames, fps=args.fps, shutter_angle=args.shutter_angle,
            method=args.method, options=options, outputs=[o.strip() for o in args.outputs.split(",") if o.strip()],
            shake=args.shake, seed=args.seed, rolling=args.rolling, width=args.width, height=args.height, client=client,
            progress=not args.no_progress, preview=args.preview, kernels=kernels,
            error_estimate=not args.no_error_estimate,
        )  # fmt: skip
    except (ValueError, TypeError, FileNotFoundError) as exc:
        print(f"motionblur dataset: {exc}", file=sys.stderr)
        return 1
    finally:
        if client is not None:
            cluster = client.cluster if args.dask == "local" else None
            client.close()
            if cluster is not None:
                cluster.close()
    print(f"{args.out}: {len(run['rendered'])} frames rendered, {len(run['skipped'])} already there")
    return 0


def _option_value(text: str):
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError):
        return text  # a bare word: a string option such as filter=box


def _render(args) -> int:
    import time

    from .render import render
    from .scene import Scene

    options = {}
    for item in args.option:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            print(f"motionblur render: --option: expected NAME=VALUE, got {item!r}", file=sys.stderr)
            return 2
        options[name.strip()] = _option_value(value.strip())
    for name in ("tolerance", "samples"):
        if getattr(args, name) is not None:
            options[name] = getattr(args, name)
    if not str(args.out).lower().endswith((".png", ".exr")):
        print(
            f"motionblur render: --out: expected a name ending in .png or .exr, got {args.out!r}",
            file=sys.stderr,
        )
        return 2
    try:
        kw = {"shutter": tuple(args.shutter)} if args.shutter else {}
        scene = Scene.from_gltf(args.file, width=args.width, height=args.height, **kw)
        t0 = time.perf_counter()
        frame = render(scene, args.method, **options)
        seconds = time.perf_counter() - t0
        if str(args.out).lower().endswith(".exr"):
            frame.save_exr(args.out)
        else:
            frame.save_png(args.out)
    except (ValueError, TypeError, FileNotFoundError) as exc:
        print(f"motionblur render: {exc}", file=sys.stderr)
        return 1
    estimate = frame.stats.get("error_estimate")
    said = f", estimated RMSE against the exact frame {estimate:.2g}" if estimate is not None else ""
    print(f"{args.out}: {args.method}, {frame.width}x{frame.height} in {seconds * 1e3:.1f} ms{said}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
