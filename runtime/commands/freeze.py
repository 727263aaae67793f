"""``wmr freeze``: compile a controller's configuration into the firmware.

    wmr freeze --controller tdroc [--formulation minimal] [--experiment FILE]
               [--robot ROBOT] [--generated DIR] [--nominal KEY=VALUE ...]
               [--set FIELD=VALUE ...] [--float32] [--force] --out DIR [--check]

``--robot`` is what every command takes (a robot file, a generated folder, or a generated
robot's name: :func:`runtime.bindings.robots.resolve`); the controller is one generated for
it. Fills the controller's configuration (:func:`runtime.bindings.config.controller_config`)
from the experiment file (default: the paper's setting), scaled to the robot as every
command scales it, the robot's nominal parameters (``--nominal`` overrides them) and
``--set`` for any field of the configuration struct (``k1=4,4,4,2,2``, ``gain0=0.5``,
``hold_gain=1`` ...); validates it and runs ``_init`` with the generated C on this machine
(see :mod:`runtime.freeze.header`), and writes ``DIR/<prefix>_<controller>_frozen.h``. Build
the firmware with ``-D<PREFIX>_<CONTROLLER>_FROZEN`` and ``DIR`` on the include path.

Before writing, the configuration's sampled closed loop is analysed as ``wmr stability``
does (:func:`runtime.stability.analysis.configuration_verdict`: its robot, h, gains,
estimator and switching gain, the experiment's sensing): one predicted unstable is refused
(exit 2, naming the verdict and a formulation predicted stable) unless ``--force``. Without
``--formulation`` the paper formulation is frozen if it is predicted stable, else the
minimal one. The verdict is written into the header's comment. Where the analysis does not
cover the robot or the controller, the header says so.

``--check`` writes nothing and exits 1 if that file is missing or its configuration,
state or code identity differ (the provenance comment is not compared). Exit status 2,
with a sentence naming the field, for a configuration the C refuses and for bad
arguments; nothing is written then.
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import sys
import tempfile
from pathlib import Path
from typing import Any

from runtime.bindings import cbuild
from runtime.bindings.config import controller_config
from runtime.bindings.generated import RobotCode
from runtime.bindings.robots import RobotSetup, RobotSourceError
from runtime.commands.options import GENERATED_HELP, ROBOT_HELP, loaded_setting
from runtime.commands.output_folder import OutputFolderError, writable_folder
from runtime.experiment.settings import Experiment, ExperimentFileError, load_experiment
from runtime.freeze.header import FreezeError, describe_error, freeze
from runtime.stability.analysis import configured_experiment
from runtime.stability.sampled_loop import NotLinearisable, covers, refusal
from runtime.stability.saturation import SaturationVerdict, grip_line, saturation_verdict


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(
        prog="wmr freeze",
        description="Validate a controller configuration with the generated C and write it, "
        "with the state _init derives from it, as a header the firmware compiles in.",
        epilog="Then build the firmware with -D<PREFIX>_<CONTROLLER>_FROZEN and -IDIR, and "
        "pass &<prefix>_<controller>_frozen_config to _init and _step. Exit status: 0 "
        "written (or up to date), 1 stale or missing (--check), 2 refused or bad arguments.",
    )
    p.add_argument("--controller", required=True, metavar="NAME",
                   help="a controller generated for the robot (tdc, tdroc, roc, asmc, ...)")
    p.add_argument("--formulation", default=None, choices=("paper", "minimal"),
                   help="default: paper if predicted stable on this robot, else minimal")
    p.add_argument("--experiment", metavar="FILE",
                   help="experiment file ([controller], [sensing]; default: the paper's)")
    p.add_argument("--robot", metavar="ROBOT", help=ROBOT_HELP)
    p.add_argument("--generated", type=Path, metavar="DIR", help=GENERATED_HELP)
    p.add_argument("--nominal", action="append", default=[], metavar="KEY=VALUE",
                   help="a nominal parameter of M-hat (default: the robot file's value)")
    p.add_argument("--set", action="append", default=[], metavar="FIELD=VALUE",
                   help="a configuration field, after the experiment's (arrays: "
                   "comma-separated, or one value for every entry)")
    p.add_argument("--float32", action="store_true",
                   help="for builds with -D<PREFIX>_FLOAT32 (the values are rounded to float "
                   "and _init runs in float)")
    p.add_argument("--force", action="store_true",
                   help="freeze a configuration the sampled-data analysis predicts unstable")
    p.add_argument("--out", required=True, type=Path, metavar="DIR",
                   help="folder of the header")
    p.add_argument("--check", action="store_true",
                   help="write nothing; exit 1 if DIR's header is missing or differs")
    return p.parse_args(argv)


def _number(option: str, key: str, value: str) -> float:
    try:
        number = float(value)
    except ValueError:
        raise FreezeError(f"{option} {key}={value!r}: not a number") from None
    if not math.isfinite(number):
        raise FreezeError(f"{option} {key}={value}: not finite")
    return number


def _pair(option: str, item: str) -> tuple[str, str]:
    key, sep, value = item.partition("=")
    if not sep or not key:
        raise FreezeError(f"{option} {item!r}: expected KEY=VALUE")
    return key, value


def nominal_params(defaults: dict[str, float], overrides: list[str]) -> dict[str, float]:
    """The robot's parameters with ``KEY=VALUE`` overrides; unknown keys, non-numbers and
    non-finite values are errors naming them."""
    params = dict(defaults)
    for item in overrides:
        key, value = _pair("--nominal", item)
        if key not in params:
            raise FreezeError(f"--nominal {key}: not a parameter of this robot "
                              f"({', '.join(params)})")
        params[key] = _number("--nominal", key, value)
    return params


def set_fields(ffi: Any, config: Any, items: list[str]) -> None:
    """``--set FIELD=VALUE``: a scalar, or an array's entries (comma-separated, or one
    value for all); integers where the field is an int. The C validates the result."""
    fields = {name: f.type for name, f in ffi.typeof(config[0]).fields if name != "nominal"}
    for item in items:
        key, value = _pair("--set", item)
        if key not in fields:
            raise FreezeError(f"--set {key}: not a field of this configuration "
                              f"({', '.join(fields)}; nominal parameters: --nominal)")
        ctype = fields[key]
        if ctype.kind == "array":
            values = [_number("--set", key, v) for v in value.split(",")]
            if len(values) == 1:
                values *= ctype.length
            if len(values) != ctype.length:
                raise FreezeError(f"--set {key}: {len(values)} values for {ctype.length} "
                                  "entries")
            setattr(config, key, values)
        elif ctype.cname == "int":
            number = _number("--set", key, value)
            if number != int(number) or abs(number) > 2**31 - 1:
                raise FreezeError(f"--set {key}={value}: an integer field")
            setattr(config, key, int(number))
        else:
            setattr(config, key, _number("--set", key, value))


def _setup(args: argparse.Namespace) -> tuple[RobotSetup, Experiment]:
    """The robot ``--robot``/``--generated`` name and the experiment scaled to it."""
    try:
        setting = loaded_setting(args.robot, args.generated, load_experiment(args.experiment))
    except RobotSourceError as exc:
        raise FreezeError(str(exc)) from None
    try:
        setting.robot.code.controller(args.controller)
    except ValueError as exc:
        raise FreezeError(f"--controller: {exc}") from None
    return setting.robot, setting.experiment


def _config(lib: cbuild.CLibrary, code: RobotCode, args: argparse.Namespace,
            formulation: str, nominal: dict[str, float], exp: Experiment) -> Any:
    if code.controller(args.controller).bounds:
        # ROC's α, φ come from sampling the model over the uncertainty box: a nominal
        # model the C refuses is named by the C before that sampling can fail on it.
        params = cbuild.params_struct(lib, nominal, f"{code.prefix}_params_t",
                                      code.controllers.C_FIELD_NAMES)
        detail = lib.ffi.new(f"{code.prefix}_error_detail_t *")
        if getattr(lib.lib, f"{code.prefix}_check_nominal")(params, detail) != 0:
            raise FreezeError(f"the {args.controller} configuration is refused: "
                              f"{describe_error(code, detail)}")
    try:
        config = controller_config(lib, code, args.controller, formulation, nominal, exp)
    except (ArithmeticError, ValueError) as exc:
        raise FreezeError(f"the {args.controller} configuration cannot be filled for this "
                          f"nominal model: {exc}") from None
    set_fields(lib.ffi, config, args.set)
    return config


def _has_verdict(code: RobotCode, controller: str) -> bool:
    """Whether the sampled-data analysis covers this robot's code (any robot whose first
    coordinates are the root's pose) and this controller's law."""
    return covers(code) and not refusal(code.controller(controller))


def choose_formulation(
    lib: cbuild.CLibrary, code: RobotCode, args: argparse.Namespace, nominal: dict[str, float],
    exp: Experiment,
) -> tuple[str, Any, list[str]]:
    """(formulation, its filled configuration, the verdict lines for the header). The one
    asked for, or paper if predicted stable, else minimal. Raises FreezeError for a
    configuration predicted unstable, unless --force."""
    from runtime.stability.analysis import configuration_verdict

    available = code.controller(args.controller).formulations  # paper first where generated
    if args.formulation is not None and args.formulation not in available:
        raise FreezeError(f"robot {code.name} has no {args.formulation} formulation generated "
                          f"for {args.controller}: use --formulation "
                          f"{' or '.join(available)}")
    candidates = (args.formulation,) if args.formulation else available
    if not _has_verdict(code, args.controller):
        form = candidates[0]
        note = (f"no sampled-data verdict for robot {code.name}: `wmr stability` needs the "
                "root's pose as its first coordinates" if not covers(code) else
                f"no sampled-data verdict: {refusal(code.controller(args.controller))}")
        print(f"note: {note}", file=sys.stderr)
        return (form, _config(lib, code, args, form, nominal, exp),
                [f"Sampled-data verdict: {note}"])
    verdicts = []
    for form in available:
        config = _config(lib, code, args, form, nominal, exp)
        _validated(lib, code, args.controller, config)
        try:
            verdicts.append((form, config, configuration_verdict(
                code, args.controller, form, nominal, exp, config)))
        except NotLinearisable as exc:  # no verdict: said in the header, never another's
            if form == candidates[0]:
                print(f"note: no sampled-data verdict: {exc}", file=sys.stderr)
                return form, config, [f"Sampled-data verdict: none: {exc}"]
    chosen = next((v for v in verdicts if v[0] in candidates and v[2].stable), None)
    if chosen is None:
        asked = next(v for v in verdicts if v[0] == candidates[0])
        stable = [v for v in verdicts if v[2].stable]
        hint = (f"; {stable[0][2].controller}/{stable[0][0]} is predicted stable (spectral "
                f"radius {stable[0][2].spectral_radius:.3f}): use --formulation {stable[0][0]}"
                if stable else "; no formulation is predicted stable")
        if not args.force:
            where = f"robot {code.name}" + (" with the --nominal parameters" if args.nominal
                                            else "")
            raise FreezeError(f"{asked[2].describe()} on {where}{hint}, or --force to freeze "
                              "it anyway (see `wmr stability`)")
        print(f"warning: {asked[2].describe()}; frozen anyway (--force)", file=sys.stderr)
        return asked[0], asked[1], [f"Sampled-data verdict: {asked[2].describe()} (frozen "
                                    "with --force)"]
    if args.formulation is None and chosen[0] != available[0]:
        print(f"note: {verdicts[0][2].describe()}; freezing the {chosen[0]} formulation",
              file=sys.stderr)
    return chosen[0], chosen[1], [f"Sampled-data verdict: {chosen[2].describe()}"]


def grip_verdict(code: RobotCode, controller: str, formulation: str,
                 nominal: dict[str, float], exp: Experiment, config: Any
                 ) -> SaturationVerdict | None:
    """``wmr stability``'s saturation and grip verdict
    (:func:`runtime.stability.saturation.saturation_verdict`, simulated) at the
    configuration's own h, gains and τ_max and the experiment's floor; None if it cannot
    be computed for this robot (the header then says why not)."""
    try:
        return saturation_verdict(code, controller, formulation, nominal,
                                  configured_experiment(code, controller, exp, config),
                                  simulate=True)
    except ValueError:
        return None


def grip_verdict_line(grip: SaturationVerdict | None) -> str:
    """The header's grip line, in :func:`~runtime.stability.saturation.grip_line`'s words;
    anything but ``ok`` is printed as a warning too (the floor is the experiment's, not
    the firmware's: it is not refused)."""
    if grip is None:
        return "Grip verdict: not available (no saturation verdict for this robot)"
    line = f"Grip verdict: {grip_line(grip)}"
    if grip.verdict != "ok":
        print(f"warning: {line}", file=sys.stderr)
    return line


def _not_stable(line: str) -> str:
    """A sampled-data verdict line without "stable" where the grip verdict says slips."""
    return line.replace(" stable: spectral radius",
                        " linearly stable but slips (grip verdict below): spectral radius")


def _validated(lib: cbuild.CLibrary, code: RobotCode, name: str, config: Any) -> None:
    """The C's check of ``config``, so that only a valid configuration is analysed."""
    detail = lib.ffi.new(f"{code.prefix}_error_detail_t *")
    if getattr(lib.lib, f"{code.prefix}_{name}_check_config_detail")(config, detail) != 0:
        raise FreezeError(f"the {name} configuration is refused: {describe_error(code, detail)}")


def audit_lines(setup: RobotSetup) -> list[str]:
    """The header comment's record of the physics audit's warnings on the robot file (as
    MODEL.md lists them): the firmware carries what was doubtful about its numbers."""
    if not setup.warnings:
        return []
    return [f"Robot file audit ({len(setup.warnings)} warning"
            f"{'s' if len(setup.warnings) > 1 else ''}; see MODEL.md):",
            *[f"  warning: {w}" for w in setup.warnings]]


def header_body(text: str) -> str:
    """What ``--check`` compares: the header from its include guard on (the configuration,
    the state and the code identity), not the provenance comment above it."""
    start = text.find("#ifndef ")
    return text[start:] if start >= 0 else text


def write_header(path: Path, text: str) -> None:
    """``text`` into ``path`` through a temporary file in the same folder: a reader never
    sees half a header, and a failure leaves the previous one. The file keeps the previous
    one's permissions, else the umask's (mkstemp's 0600 would lock other users out)."""
    if path.is_dir():
        raise OutputFolderError(f"--out: {path} is a folder")
    if path.exists():
        mode = path.stat().st_mode & 0o777
    else:
        umask = os.umask(0)
        os.umask(umask)
        mode = 0o666 & ~umask
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.chmod(tmp, mode)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    try:
        if shutil.which("gcc") is None:
            raise FreezeError("wmr freeze validates with the generated C: it needs gcc on "
                              "the PATH")
        setup, exp = _setup(args)
        code = setup.code
        nominal = nominal_params(setup.nominal, args.nominal)
        lib = cbuild.build(args.float32, c_dir=code.c_dir, prefix=code.prefix)
        formulation, config, verdict = choose_formulation(lib, code, args, nominal, exp)
        grip = grip_verdict(code, args.controller, formulation, nominal, exp, config)
        if grip is not None and grip.verdict == "slips":  # "stable" is not said then
            verdict = [_not_stable(line) for line in verdict]
        verdict = [*verdict, grip_verdict_line(grip)]
        made_from = (
            f"Made by: wmr freeze --controller {args.controller} --formulation "
            f"{formulation}{' --float32' if args.float32 else ''}"
            f"{' --force' if args.force else ''}",
            f"Experiment: {args.experiment or 'the paper setting (no --experiment)'}",
            "Nominal parameters: " + ", ".join(f"{k} = {v!r}" for k, v in nominal.items()),
            *([f"Set: {' '.join(args.set)}"] if args.set else []),
            *verdict,
            *audit_lines(setup),
        )
        frozen = freeze(lib, code, args.controller, config, made_from)
        target = args.out / frozen.filename
        if args.check:
            current = target.read_text(encoding="utf-8") if target.is_file() else None
            if current is not None and header_body(current) == header_body(frozen.text):
                print(f"{target}: up to date")
                return 0
            print(f"{target}: {'missing' if current is None else 'stale'}; rerun without "
                  "--check", file=sys.stderr)
            return 1
        writable_folder(args.out)
        write_header(target, frozen.text)
    except (FreezeError, ExperimentFileError, OutputFolderError, cbuild.BuildError,
            OSError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {target}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
