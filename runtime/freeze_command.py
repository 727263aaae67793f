"""``wmr freeze``: compile a controller's configuration into the firmware.

    wmr freeze --controller tdroc [--formulation minimal] [--experiment FILE]
               [--robot NAME_OR_DIR] [--nominal KEY=VALUE ...] [--float32] --out DIR [--check]

Fills the controller's configuration from the experiment file's ``[controller]`` and
``[sensing]`` tables (default: the paper's setting) and the robot's nominal parameters,
validates it and runs ``_init`` with the generated C on this machine (see
:mod:`runtime.frozen_config`), and writes ``DIR/<prefix>_<controller>_frozen.h``. Build the
firmware with ``-D<PREFIX>_<CONTROLLER>_FROZEN`` and ``DIR`` on the include path.
``--check`` writes nothing and exits 1 if that file is missing or differs (stale after
``wmr model`` or a changed experiment). Exit status 2 for a configuration the C refuses or
bad arguments, naming the field.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
from pathlib import Path

from runtime import cbuild
from runtime.experiment import ExperimentFileError, load_experiment
from runtime.frozen_config import FreezeError, freeze
from runtime.output_folder import OutputFolderError, writable_folder
from runtime.robot_simulation import controller_config

CONTROLLERS = ("tdc", "tdroc", "roc", "asmc")


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(
        prog="wmr freeze",
        description="Validate a controller configuration with the generated C and write it, "
        "with the state _init derives from it, as a header the firmware compiles in.",
    )
    p.add_argument("--controller", required=True, choices=CONTROLLERS)
    p.add_argument("--formulation", default="paper", choices=("paper", "minimal"))
    p.add_argument("--experiment", metavar="FILE",
                   help="experiment file ([controller], [sensing]; default: the paper's)")
    p.add_argument("--robot", metavar="NAME_OR_DIR",
                   help="a generated robot's name or folder (default: the paper's robot)")
    p.add_argument("--nominal", action="append", default=[], metavar="KEY=VALUE",
                   help="a nominal parameter of M-hat (default: the robot file's value)")
    p.add_argument("--float32", action="store_true",
                   help="for builds with -D<PREFIX>_FLOAT32 (the values are rounded to float "
                   "and _init runs in float)")
    p.add_argument("--out", required=True, type=Path, metavar="DIR",
                   help="folder of the header")
    p.add_argument("--check", action="store_true",
                   help="write nothing; exit 1 if DIR's header is missing or differs")
    return p.parse_args(argv)


def nominal_params(defaults: dict[str, float], overrides: list[str]) -> dict[str, float]:
    """The robot's parameters with ``KEY=VALUE`` overrides; unknown keys, non-numbers and
    non-finite values are errors naming them."""
    params = dict(defaults)
    for item in overrides:
        key, sep, value = item.partition("=")
        if not sep:
            raise FreezeError(f"--nominal {item!r}: expected KEY=VALUE")
        if key not in params:
            raise FreezeError(f"--nominal {key}: not a parameter of this robot "
                              f"({', '.join(params)})")
        try:
            number = float(value)
        except ValueError:
            raise FreezeError(f"--nominal {key}={value!r}: not a number") from None
        if not math.isfinite(number):
            raise FreezeError(f"--nominal {key}={value}: not finite")
        params[key] = number
    return params


def write_atomically(path: Path, text: str) -> None:
    """``text`` into ``path`` through a temporary file in the same folder: a reader never
    sees half a header, and a failure leaves the previous one."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    from runtime.generated_modules import load_robot_code
    from runtime.tooling.crosscheck.targets import resolve

    try:
        code = resolve(args.robot).code if args.robot else load_robot_code("")
        if args.formulation == "paper" and not hasattr(code.controllers,
                                                      "FORMULATION_PAPER"):
            raise FreezeError(f"robot {code.name} has no paper formulation generated: "
                              "use --formulation minimal")
        exp = load_experiment(args.experiment)
        nominal = nominal_params(code.params, args.nominal)
        if not args.check:
            writable_folder(args.out)
        lib = cbuild.build(args.float32, c_dir=code.c_dir, prefix=code.prefix)
        config = controller_config(lib, code, args.controller, args.formulation, nominal, exp)
        made_from = (
            f"Made by: wmr freeze --controller {args.controller} --formulation "
            f"{args.formulation}{' --float32' if args.float32 else ''}",
            f"Experiment: {args.experiment or 'the paper setting (no --experiment)'}",
            "Nominal parameters: " + ", ".join(f"{k} = {v:g}" for k, v in nominal.items()),
        )
        frozen = freeze(lib, code, args.controller, config, made_from)
    except (FreezeError, ExperimentFileError, OutputFolderError, FileNotFoundError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    target = args.out / frozen.filename
    if args.check:
        current = target.read_text(encoding="utf-8") if target.is_file() else None
        if current == frozen.text:
            print(f"{target}: up to date")
            return 0
        print(f"{target}: {'missing' if current is None else 'stale'}; rerun without --check",
              file=sys.stderr)
        return 1
    write_atomically(target, frozen.text)
    print(f"wrote {target}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
