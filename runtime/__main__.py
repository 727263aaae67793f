"""``python -m runtime <command>``: crosscheck, reproduce, bench.

python -m runtime crosscheck            # generated code vs hand-written equations
python -m runtime reproduce [--experiment F.toml] [--robot F.toml] [--out DIR]
python -m runtime stability [--experiment F.toml] [--robot F.toml] [--json]
python -m runtime bench [--quick]
python -m runtime campaign [--spec F.toml] [--robot F] [--runs N] [--scheduler ADDR]
                           [--workers N] --out DIR
"""

from __future__ import annotations

import argparse
import importlib
import sys

# command -> the module whose main(argv) runs it
COMMANDS = {
    "crosscheck": "runtime.tooling.crosscheck.command",
    "reproduce": "runtime.reproduce_command",
    "stability": "runtime.paper.stability",
    "bench": "runtime.tooling.bench.report",
    "campaign": "runtime.campaign.command",
}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m runtime", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser(
        "crosscheck", help="compare every implementation with the hand-written one", add_help=False
    )
    sub.add_parser(
        "reproduce", help="run the paper's experiments, write plots and tables", add_help=False
    )
    sub.add_parser(
        "stability",
        help="predict each controller's sampled-data stability on a robot",
        add_help=False,
    )
    sub.add_parser("bench", help="benchmark the generated code", add_help=False)
    sub.add_parser(
        "campaign", help="closed-loop runs over the uncertainty box on Dask", add_help=False
    )
    args, rest = parser.parse_known_args(argv)
    # Imported on demand: each command pulls in only what it needs.
    module = importlib.import_module(COMMANDS[args.command])
    status: int = module.main(rest)
    return status


if __name__ == "__main__":
    sys.exit(main())
