"""Command line: ``python -m motionblur demo|bench``."""

from __future__ import annotations

import argparse
import sys


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m motionblur")
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="render the built-in scenes, write images and a speed/error table")
    demo.add_argument("--out", default="out/demo")
    args = parser.parse_args(argv)
    if args.command == "demo":
        from .demo import run

        return run(args.out)
    return 2


if __name__ == "__main__":
    sys.exit(main())
