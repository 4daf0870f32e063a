"""Command line: ``python -m motionblur demo [--out DIR]`` and ``python -m motionblur bench [options]``."""

from __future__ import annotations

import argparse
import sys


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m motionblur")
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
    if argv[:1] == ["bench"]:
        from .evaluation.bench import main as bench_main

        return bench_main(argv[1:])
    args = parser.parse_args(argv)
    if args.command == "demo":
        from .evaluation.demo import run

        return run(args.out)
    return 2


if __name__ == "__main__":
    sys.exit(main())
