"""``wmr``: the toolchain's command line (also ``python -m runtime``).

    wmr model [--robot FILE] [--out DIR]       derive robots, generate C, NumPy and CasADi
    wmr check [--robot FILE] [--out DIR]       exit 1 if generated code is stale
    wmr mjcf [--robot FILE] --out FILE.xml     the robot as a MuJoCo model (MJCF)
    wmr reproduce [--robot ROBOT] [--out DIR]  the paper's experiments, or scaled to a robot
    wmr crosscheck [--robot ROBOT]             every implementation against the hand-written
    wmr stability [--robot ROBOT]              sampled-data stability of each controller
    wmr faults [--robot ROBOT] [--out DIR]     encoder, sample, traction, torque faults
    wmr campaign [--robot ROBOT] [--spec FILE] [--runs N] --out DIR  robustness campaigns
    wmr bench                                  benchmarks of the generated code
    wmr firmware                               Cortex-M4 size, stack and instruction counts
    wmr freeze --controller NAME [--robot ROBOT] --out DIR  a configuration for firmware

ROBOT, for every command that runs one: a robot file (lumped, physical, or bodies and
wheels), a generated folder (``wmr model --out DIR``), or the name of a robot generated
under ``generated/``; ``--generated DIR`` says where a robot file's code is, and
``--experiment FILE`` the experiment, scaled to the robot the same way by every command
(``runtime.commands.options``). Each subcommand has its own ``--help``. A command's
module (``runtime.commands.*``, or a tool's) is named here as a string and imported only
when it runs, so ``wmr reproduce`` never imports SymPy or the code generator.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import sys
from dataclasses import dataclass


@dataclass(frozen=True)
class Command:
    """A subcommand: the module whose ``main(argv)`` runs it, and arguments it always gets."""

    module: str
    help: str
    fixed_args: tuple[str, ...] = ()
    extra: str = ""  # the optional dependencies it needs: pip install 'wmr-toolchain[extra]'
    needs: tuple[str, ...] = ()  # the modules of that extra


COMMANDS: dict[str, Command] = {
    "model": Command("codegen.__main__", "derive robots and generate their code"),
    "import": Command("modeling.importers.command", "URDF/MJCF in, an audited robot file out"),
    "mjcf": Command("modeling.mjcf_command", "a robot file as a MuJoCo model (MJCF)"),
    "check": Command(
        "codegen.__main__", "exit 1 with a diff if generated code is stale", ("--check",)
    ),
    "reproduce": Command(
        "runtime.commands.reproduce", "run the paper's experiments, write plots and tables"
    ),
    "crosscheck": Command(
        "runtime.tooling.crosscheck.command",
        "compare every implementation with the hand-written one",
    ),
    "stability": Command(
        "runtime.commands.stability",
        "predict each controller's sampled-data stability on a robot",
    ),
    "faults": Command(
        "runtime.commands.faults",
        "sensor and actuator faults in the closed loop: what each controller reports",
    ),
    "campaign": Command(
        "runtime.commands.campaign",
        "thousands of closed-loop runs over the uncertainty box, on Dask",
        extra="campaign",
        needs=("dask", "distributed", "pyarrow", "tqdm"),
    ),
    "bench": Command("runtime.tooling.bench.report", "benchmark the generated code"),
    "firmware": Command(
        "runtime.tooling.firmware.report",
        "Cortex-M4 code size, stack and emulated instructions of the generated C",
    ),
    "freeze": Command(
        "runtime.commands.freeze",
        "validate a controller configuration and write it as a header firmware compiles in",
    ),
}


def parser(prog: str) -> argparse.ArgumentParser:
    from modeling.version import VERSION

    p = argparse.ArgumentParser(
        prog=prog,
        description="From a wheeled robot's Lagrangian to verified controller firmware.",
        epilog="Run `%(prog)s COMMAND --help` for a command's options.",
    )
    p.add_argument("--version", action="version", version=f"wmr-toolchain {VERSION}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, cmd in COMMANDS.items():
        sub.add_parser(name, help=cmd.help, add_help=False)
    return p


def missing_extra(name: str, cmd: Command) -> str | None:
    """The error for a command whose optional dependencies are not installed, else None."""
    missing = [m for m in cmd.needs if importlib.util.find_spec(m) is None]
    if not missing:
        return None
    return (f"wmr {name} needs the '{cmd.extra}' extra: pip install 'wmr-toolchain[{cmd.extra}]'"
            f" (missing: {', '.join(missing)})")


def main(argv: list[str] | None = None, prog: str = "wmr") -> int:
    args, rest = parser(prog).parse_known_args(argv)
    cmd = COMMANDS[args.command]
    error = missing_extra(args.command, cmd)
    if error is not None:
        print(f"error: {error}", file=sys.stderr)
        return 2
    module = importlib.import_module(cmd.module)
    status: int = module.main([*cmd.fixed_args, *rest])
    return status


if __name__ == "__main__":
    sys.exit(main())
