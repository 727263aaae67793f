"""``python -m runtime <command>``: crosscheck, reproduce, bench.

    python -m runtime crosscheck            # generated code vs hand-written equations
    python -m runtime reproduce [--experiment F.toml] [--out DIR] [--quick]
    python -m runtime bench [--quick]
"""

from __future__ import annotations

import argparse
import sys


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m runtime", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("crosscheck", help="compare every implementation with the hand-written one",
                   add_help=False)
    sub.add_parser("reproduce", help="run the paper's experiments, write plots and tables",
                   add_help=False)
    sub.add_parser("bench", help="benchmark the generated code", add_help=False)
    args, rest = parser.parse_known_args(argv)
    if args.command == "crosscheck":
        from runtime import crosscheck

        return crosscheck.main(rest)
    if args.command == "reproduce":
        from runtime import reproduce

        return reproduce.main(rest)
    from runtime import bench

    return bench.main(rest)


if __name__ == "__main__":
    sys.exit(main())
