"""What the generated controller step functions are: names, statuses, configuration.

Shared by the C and Python controller templates so both APIs stay mirror images. The
arithmetic lives in the ``<prefix>_laws`` kernels (codegen.robot_functions); a step
function validates, keeps the history, calls the kernels, saturates and commits. Names and
sizes come from the robot's ``codegen.controller_layout.ControllerLayout``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from codegen.controller_layout import ControllerLayout, words
from codegen.robot_functions import MAX_WINDOW
from codegen.spec import StatusCode
from modeling.controllers import (
    BASE_CHECKS,
    REGISTRY,
    SHARED_FIELDS,
    ConfigField,
    ControllerSpec,
    KernelArg,
    kernel,
)
from modeling.robot_model import RobotModel

# Input magnitudes beyond this are rejected as absurd (a lying sensor), not clipped.
MAX_ABS_INPUT = "1.0e6"

# Plausibility bounds of the configuration (issue 13): an accepted configuration must not
# be able to put a value into the state from which a later valid step cannot succeed.
H_MIN = "1.0e-6"  # sample time [s]: a 1 MHz loop at most ...
H_MAX = "1.0"  # ... and a 1 Hz loop at least
GAIN_MAX = "1.0e6"  # K1, K2, Q, eps, phi, gamma, held_gain, gain0; and the adaptive gains' cap
# K1, K2, Q and eps from below (issue 25): gain / eps, P of (20) and every ratio of them stay
# finite in float32, so no accepted value can form inf * 0 (an eps of 2^-1074 made a step
# with exactly zero error return NaN: (k / eps) * 0).
GAIN_MIN = "1.0e-6"
TORQUE_LIMIT_MAX = "1.0e6"  # tau_max [N m]
NOMINAL_FACTOR = "1.0e3"  # |nominal p| <= NOMINAL_FACTOR * max(|robot file's p|, 1), and a
# parameter the model needs positive >= its robot file's value / NOMINAL_FACTOR (issue 25: a
# wheel radius of 1e-30 m was accepted and overflowed M-hat in float32)
STEPS_MAX = "4294967295"  # the saturating step counter (uint32_t)

# What an error can be about besides a configuration field (``<prefix>_field_t``), with its
# stable number: (number, name, doc). The configuration fields bring their own
# (``ConfigField.field_id``); ``detail_fields`` merges them. Append, never renumber.
STEP_SUBJECTS: tuple[tuple[int, str, str], ...] = (
    (0, "NONE", "no error"),
    (1, "STATE", "the state pointer, or a state never initialised"),
    (2, "CONFIG", "the config pointer, or a config changed since _init"),
    (3, "Q", "q[index]"),
    (4, "QDOT", "qdot[index]"),
    (5, "Q_DES", "q_des[index]"),
    (6, "QDOT_DES", "qdot_des[index]"),
    (7, "QDDOT_DES", "qddot_des[index]"),
    (8, "TAU", "tau (NULL), or the torque tau[index] computed"),
    (9, "NOMINAL", "nominal parameter index (struct order); -1: the parameters together"),
    (28, "GAIN", "the switching gain computed"),
    (29, "S_NORM", "||s|| computed"),
    (30, "U_DISCARDED", "||u rows dropped by tau = B^T u|| computed"),
    (31, "P", "P of (20) from k1[index], k2[index], q_pos, q_vel is not finite"),
)


def registry_fields(controllers: Sequence[ControllerSpec]) -> tuple[ConfigField, ...]:
    """Every configuration field of ``controllers``, once each, in registry order (a field
    that two controllers have is one declaration: two different ones of one name are
    refused)."""
    seen: dict[str, ConfigField] = {}
    for c in controllers:
        for f in c.fields:
            if seen.setdefault(f.name, f) != f:
                raise ValueError(f"controller {c.name}: field {f.name!r} differs from "
                                 "another controller's field of that name")
    return tuple(seen.values())


def detail_fields(controllers: Sequence[ControllerSpec]) -> tuple[tuple[str, str], ...]:
    """``<prefix>_field_t`` in value order, (name, doc): ``STEP_SUBJECTS`` and every
    configuration field of ``controllers`` at its ``field_id``, then the fields without one
    in registry order. The numbered ones must be 0, 1, ... without a gap or a repeat."""
    numbered = [(i, name, doc) for i, name, doc in STEP_SUBJECTS]
    rest = []
    for f in registry_fields(controllers):
        if f.field_id is None:
            rest.append((f.name.upper(), f.detail_doc))
        else:
            numbered.append((f.field_id, f.name.upper(), f.detail_doc))
    numbered.sort()
    if [i for i, _, _ in numbered] != list(range(len(numbered))):
        raise ValueError("the field_id of the configuration fields and STEP_SUBJECTS must "
                         f"number 0..{len(numbered) - 1} once each: {numbered}")
    return (*((name, doc) for _, name, doc in numbered), *rest)


# Which input or field an error is about (``<prefix>_field_t``), for the registry.
FIELDS: tuple[tuple[str, str], ...] = detail_fields(REGISTRY)
FIELD_IDS: dict[str, int] = {name: i for i, (name, _) in enumerate(FIELDS)}


def status_codes(layout: ControllerLayout) -> tuple[StatusCode, ...]:
    """The values of ``<prefix>_status_t`` (names carry ``layout.PREFIX``)."""
    P = layout.PREFIX
    formulations = "PAPER or MINIMAL" if layout.paper else "MINIMAL (the only one generated)"
    return (
        StatusCode(f"{P}_OK", 0, "success"),
        StatusCode(f"{P}_WARN_SATURATED", 1, "success, but a torque was clipped to the limit"),
        StatusCode(f"{P}_WARN_TRACTION", 2,
                   "traction_check: a driven wheel's traction margin is <= 0 (it slips)"),
        StatusCode(f"{P}_WARN_UNCERTIFIED", 3,
                   "within_certificate: the last step's switching gain or (25)'s inputs left "
                   "the float32 certificate's box (its torque bound does not apply)"),
        StatusCode(f"{P}_ERR_NULL_POINTER", -1, "a pointer argument is NULL"),
        StatusCode(f"{P}_ERR_NONFINITE_INPUT", -2, "an input is NaN or infinite"),
        StatusCode(f"{P}_ERR_BAD_PARAMS", -3, "robot parameters do not give a valid model"),
        StatusCode(f"{P}_ERR_NONFINITE_OUTPUT", -4, "a result is not finite"),
        StatusCode(f"{P}_ERR_BAD_MEASUREMENT", -5, "q or qdot is NaN, infinite or absurdly large"),
        StatusCode(f"{P}_ERR_BAD_REFERENCE", -6, "a reference is NaN, infinite or absurdly large"),
        StatusCode(
            f"{P}_ERR_BAD_EPS", -7, f"boundary layer eps outside [{P}_GAIN_MIN, {P}_GAIN_MAX]"
        ),
        StatusCode(f"{P}_ERR_BAD_WINDOW", -8, f"window n outside 2..{P}_MAX_WINDOW"),
        StatusCode(f"{P}_ERR_BAD_DISCOUNT", -9, "discount a outside (0, 1]"),
        StatusCode(f"{P}_ERR_BAD_SAMPLE_TIME", -10, "h <= 0 or not finite"),
        StatusCode(
            f"{P}_ERR_BAD_GAINS", -11,
            f"a K1, K2 or Q entry outside [{P}_GAIN_MIN, {P}_GAIN_MAX], or P of (20) not finite",
        ),
        StatusCode(f"{P}_ERR_BAD_NOMINAL", -12, "nominal parameters give a singular M-hat"),
        StatusCode(f"{P}_ERR_BAD_TORQUE_LIMIT", -13, "torque limit <= 0 or NaN"),
        StatusCode(f"{P}_ERR_BAD_FORMULATION", -14, f"formulation is not {formulations}"),
        StatusCode(
            f"{P}_ERR_NOT_INITIALISED", -15,
            "state not initialised by _init, or corrupted (an index it holds out of range)",
        ),
        StatusCode(
            f"{P}_ERR_BAD_BOUNDS", -16, "ROC alpha outside [0, 1) or phi < 0; ASMC gamma/gain < 0"
        ),
        StatusCode(
            f"{P}_ERR_BAD_ESTIMATOR",
            -17,
            "accel_estimator is not BACKWARD, CENTRAL or MATCHED, or rate_window is outside [0, h]",
        ),
        StatusCode(
            f"{P}_ERR_BAD_HELD_GAIN", -18, "TDROC hold_gain is not 0 or 1, or held_gain < 0"
        ),
        StatusCode(
            f"{P}_ERR_CONFIG_CHANGED",
            -19,
            "the configuration differs from the one given to _init (any bit of any value)",
        ),
        StatusCode(f"{P}_ERR_BAD_TRACTION", -20,
                   "traction check: friction coefficient or a wheel load <= 0, mu N outside"
                   " [1e-30, 1e30] N or a share outside [0, 1]"),
    )


def defines(layout: ControllerLayout) -> tuple[tuple[str, str, str], ...]:
    """Integer constants of ``<prefix>_types.h``: (name, value, doc)."""
    P = layout.PREFIX
    paper_doc = f"the {words(layout.nq)} coordinates of (14), tau = B^T u"
    if not layout.paper:
        paper_doc += f": not generated for this robot ({P}_ERR_BAD_FORMULATION)"
    return (
        (f"{P}_FORMULATION_PAPER", "0", paper_doc),
        (f"{P}_FORMULATION_MINIMAL", "1", f"the {words(layout.nu)} wheel angles, tau = u"),
        (f"{P}_ACCEL_BACKWARD", "0", "qddot(t-h) = (qdot(t) - qdot(t-h))/h (default)"),
        (f"{P}_ACCEL_CENTRAL", "1", "qddot(t-h) = (qdot(t) - qdot(t-2h))/(2h)"),
        (
            f"{P}_ACCEL_MATCHED",
            "2",
            "backward quotient paired with (1-c) u(t-h) + c u(t-2h), c = rate_window/(2h)",
        ),
        (f"{P}_MAX_WINDOW", str(MAX_WINDOW), "largest TDROC window n (history size)"),
        (f"{P}_NQ", str(layout.nq), "generalised coordinates"),
        (f"{P}_STATE_MAGIC", layout.state_magic, "marks an initialised controller state"),
        (f"{P}_STEPS_MAX", STEPS_MAX + "u", "the step counter saturates here (uint32_t)"),
    )


def real_bounds() -> tuple[tuple[str, str, str], ...]:
    """Real constants of the plausibility bounds: (name without prefix, value, doc)."""
    return (
        ("H_MIN", H_MIN, "smallest sample time h [s]"),
        ("H_MAX", H_MAX, "largest sample time h [s]"),
        ("GAIN_MIN", GAIN_MIN, "smallest K1, K2 and Q entry and eps: their ratios stay finite"),
        ("GAIN_MAX", GAIN_MAX, "largest gain, eps, phi, gamma; cap of the adaptive gains"),
        ("TORQUE_LIMIT_MAX", TORQUE_LIMIT_MAX, "largest tau_max [N m]"),
        ("NOMINAL_FACTOR", NOMINAL_FACTOR, "|nominal p| <= this * max(|robot file's p|, 1)"),
    )


def c_common_context(controllers: Sequence[ControllerSpec] = REGISTRY) -> dict[str, object]:
    """What ``controller_common.{h,c}.jinja`` needs besides the robot: bounds and the fields
    an error can be about (of ``controllers``)."""
    return {"real_bounds": real_bounds(), "fields": detail_fields(controllers)}


@dataclass(frozen=True)
class StepArg:
    """A law kernel's argument as a step passes it: name, source (``STEP_SOURCES``) and,
    for a ``config`` source, the configuration fields it packs."""

    name: str
    source: str
    fields: tuple[str, ...] = ()


# What a step passes for each source of a kernel argument (modeling.controllers.KernelArg):
# the measured and desired quantities of this step, the configuration (``config``: the
# fields the argument's symbols name, a pointer to one or an array packed from several),
# the state's P, the TDE estimate, and the gains: k-hat computed this step (``khat``) or the
# state's adapted one (``adapted_gain``), and the state's integral (``integral``). Outputs:
# u, s, ||s||, the gain used or adapted, and the integral after this step.
STEP_SOURCES = ("q", "qdot", "q_des", "qdot_des", "e", "edot", "qddot_des", "k1", "k2", "p12",
                "p22", "H1hat", "khat", "adapted_gain", "integral", "config", "u", "s",
                "s_norm", "gain")


def law_signature(spec: ControllerSpec, model: RobotModel) -> tuple[list[StepArg], list[StepArg]]:
    """(inputs after the nominal parameters, outputs) of ``spec``'s kernel as a step fills
    them (the same for every formulation)."""
    k = kernel(spec, model.formulations[-1], model)

    def arg(a: KernelArg) -> StepArg:
        if a.source not in STEP_SOURCES:
            raise ValueError(f"controller {spec.name}: kernel argument {a.name} has an unknown "
                             f"source {a.source!r} (known: {', '.join(STEP_SOURCES)})")
        return StepArg(a.name, a.source, tuple(str(v) for v in a.values)
                       if a.source == "config" else ())

    return [arg(a) for a in k.inputs], [arg(a) for a in k.outputs]


def c_controller_context(
    spec: ControllerSpec, param_fields: list[str], layout: ControllerLayout, model: RobotModel
) -> dict[str, object]:
    """What ``controller.{h,c}.jinja`` needs for ``spec`` besides the robot (its C
    parameter field names, layout and model)."""
    inputs, outputs = law_signature(spec, model)
    return {"law_inputs": inputs, "law_outputs": outputs,
            "config_fields": config_fields(spec),
            "config_values": config_values(spec, param_fields),
            "config_lines": config_struct_lines(spec, layout),
            "base_checks": BASE_CHECKS, "max_window": MAX_WINDOW}


def config_values(spec: ControllerSpec, param_fields: list[str]) -> list[tuple[str, str, int]]:
    """Every value of ``<prefix>_<ctrl>_config_t`` in struct order, as (member path, "real" or
    "int", count: 0 for a vector of nq entries): the nominal parameters, then
    ``config_fields``. A step compares the caller's configuration with the copy _init kept
    value by value (C and Python alike), never padding."""
    return [(f"nominal.{f}", "real", 1) for f in param_fields] + list(config_fields(spec))


def python_context(controllers: Sequence[ControllerSpec] = REGISTRY) -> dict[str, object]:
    """What ``controllers.py.jinja`` needs besides the robot (the C constants, mirrored) for
    ``controllers``."""
    return {
        "real_bounds": real_bounds(),
        "steps_max": STEPS_MAX,
        "fields": detail_fields(controllers),
        "config_fields": {c.name: config_fields(c) for c in controllers},
        "mirror_fields": mirror_fields(controllers),
    }


def mirror_fields(controllers: Sequence[ControllerSpec]) -> tuple[ConfigField, ...]:
    """The members of the Python mirror's ``Config`` after ``nominal``: every field of
    ``controllers``, the shared ones first in their order (``SHARED_FIELDS``), then each
    law's own in registry order."""
    fields = registry_fields(controllers)
    shared = [f for f in SHARED_FIELDS if f in fields]
    return (*shared, *(f for f in fields if f not in SHARED_FIELDS))



def nominal_bound(default: float) -> float:
    """The bound on a nominal parameter's magnitude: ``NOMINAL_FACTOR * max(|default|, 1)``."""
    return float(NOMINAL_FACTOR) * max(abs(float(default)), 1.0)


def nominal_range(default: float, positive: bool) -> tuple[float, float]:
    """(lowest, highest) accepted nominal value of a parameter whose robot file's value is
    ``default``: ±``nominal_bound``, from ``default / NOMINAL_FACTOR`` up for a parameter the
    model needs positive."""
    high = nominal_bound(default)
    return (float(default) / float(NOMINAL_FACTOR) if positive else -high), high


def config_fields(spec: ControllerSpec) -> tuple[tuple[str, str, int], ...]:
    """The fields of ``<prefix>_<ctrl>_config_t`` after ``nominal``, in struct order:
    (name, "real" or "int", count; 0: nq entries), from the registry."""
    return tuple((f.name, "real" if f.kind == "vector" else f.kind, 0 if f.kind == "vector"
                  else 1) for f in spec.fields)


# The comment column of the config struct (after "    "), as for a three-letter prefix.
_COMMENT_COLUMN = 24


def config_struct_lines(spec: ControllerSpec, layout: ControllerLayout) -> list[str]:
    """The member lines of ``<prefix>_<ctrl>_config_t`` after ``nominal``: declaration and
    the field's doc as a comment aligned at one column (a continuation line under its
    text)."""
    pre = layout.prefix
    formulations = (f"{layout.PREFIX}_FORMULATION_PAPER or {layout.PREFIX}_FORMULATION_MINIMAL"
                    if layout.paper else f"{layout.PREFIX}_FORMULATION_MINIMAL (the paper "
                    "formulation is not generated)")
    actuated_k1 = ", ".join(f"k1[{a}]" for a in layout.actuated)
    lines = []
    for f in spec.fields:
        ctype = f.c_type(pre)
        dims = f"[{layout.nq}]" if f.kind == "vector" else ""
        decl = f"{ctype} {f.name}{dims};"
        doc = f.doc.format(PRE=layout.PREFIX, actuated_k1=actuated_k1,
                           formulations=formulations)
        if not doc:
            lines.append(f"    {decl}")
            continue
        width = len(f.c_type("wmr") + f" {f.name}"
                    + ("[5]" if f.kind == "vector" else "") + ";")
        first, *rest = doc.split("\n")
        pad = " " * max(1, _COMMENT_COLUMN - width)
        text = [f"    {decl}{pad}/* {first}"]
        indent = " " * (4 + width + len(pad) + 3)  # as the first line for a "wmr" prefix
        text += [f"{indent}{line}" for line in rest]
        text[-1] += " */"
        lines += text
    return lines


# The registry's controllers (modeling.controllers.REGISTRY), the default of the functions
# above; a generation reads its own (``RobotTarget.controllers``).
CONTROLLERS: tuple[ControllerSpec, ...] = REGISTRY
