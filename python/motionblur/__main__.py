"""Command line: ``motionblur demo [--out DIR]``, ``motionblur bench [options]`` and ``motionblur --version``
(also ``python -m motionblur ...``; pip installs the ``motionblur`` script)."""

from __future__ import annotations

import argparse
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
    except MissingDependencyError as exc:  # a clear line, not a traceback: what to install
        print(f"motionblur: {exc}", file=sys.stderr)
        return 1
    return 2


if __name__ == "__main__":
    sys.exit(main())
