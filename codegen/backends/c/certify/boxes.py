"""The declared input box of every generated function: where its certificate holds.

A box is an interval per input the function reads, taken from one stated operating
envelope (:class:`Envelope`) and the robot's own numbers: the parameters within
``uncertainty`` of the robot file's values (±10 %), angles within two
turns either way, rates and torques within the controllers' operating ranges
(``runtime.experiment.settings`` and ``runtime.tooling.crosscheck.inputs`` sample the same
ranges). Inputs that one generated function computes for another take that function's
certified output enclosure (:data:`DERIVED`): P's entries are those of ``lyapunov_p``
over the gains' box, never a guess. An input with no declared range is refused with its
name: a new input must be given one here. The envelope is declared in
:mod:`codegen.certify.envelope`, where the generator reads it too (the robust steps'
run-time check of their conditions, :mod:`codegen.certify.runtime_check`).
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence

import sympy as sp

from codegen.backends.c.certify.analysis import U
from codegen.backends.c.certify.program import Program
from codegen.certify.envelope import ENVELOPE, Envelope, Interval

__all__ = ["DERIVED", "ENVELOPE", "BoxError", "Envelope", "Interval", "box_of", "derived_key",
           "input_errors", "input_range", "parameter_ranges", "producers"]

# Inputs computed by another generated function: (argument, index) -> (function, output
# store). The box of the consumer is the producer's certified output enclosure.
DERIVED: Mapping[str, tuple[str, Sequence[str]]] = {
    "p12": ("lyapunov_p", ("P[1]",)),
    "p22": ("lyapunov_p", ("P[2]",)),
    # M-hat (minimal form, evaluated once a step where it depends on q): each entry its
    # own output's enclosure (independently of the others: such a box still holds
    # singular matrices, see docs/FLOAT32.md)
    **{f"{arg}[{i}]": ("minimal_mhat", (f"M[{i}]",)) for arg in ("mhat", "mhat_prev")
       for i in range(4)},
}


def derived_key(access: str) -> str:
    """The :data:`DERIVED` entry an input read as ``access`` takes its range from ("" for
    none): its own (``mhat[0]``) or its argument's (``p12[0]``), as :func:`input_range`."""
    base = access.split("[")[0]
    return access if access in DERIVED else base if base in DERIVED else ""


def producers(prog: Program) -> set[str]:
    """The functions whose outputs ``prog``'s :data:`DERIVED` inputs are (its box takes
    their enclosures)."""
    return {DERIVED[k][0] for k in map(derived_key, prog.input_names.values()) if k}


_ACCESS = re.compile(r"(\w+)(?:->(\w+)|\[(\d+)\])")


def _sym(a: float) -> Interval:
    return (-a, a)


class BoxError(ValueError):
    """An input with no declared range."""


def parameter_ranges(params: Mapping[str, float], env: Envelope) -> dict[str, Interval]:
    """C field -> the parameter's interval (its value within the stated uncertainty)."""
    out: dict[str, Interval] = {}
    for field, value in params.items():
        a, b = value * (1 - env.uncertainty), value * (1 + env.uncertainty)
        out[field] = (min(a, b), max(a, b))
    return out


def input_range(access: str, angles: Sequence[bool], params: Mapping[str, Interval],
                derived: Mapping[str, Interval], env: Envelope = ENVELOPE) -> Interval:
    """The declared interval of the input read as ``access`` (``p->m``, ``q[2]`` ...)."""
    m = _ACCESS.fullmatch(access)
    if m is None:
        raise BoxError(f"cannot read input access {access!r}")
    arg, field, index = m.group(1), m.group(2), int(m.group(3) or 0)
    if field is not None:
        if arg in ("base", "p", "pp") and field in params:
            return params[field]
        raise BoxError(f"no declared range for parameter {access}")
    if access in derived:
        return derived[access]
    if arg in derived:
        return derived[arg]
    is_angle = angles[index] if index < len(angles) else True
    table: dict[str, Interval] = {
        "q": _sym(env.angle if is_angle else env.position),
        "q_prev": _sym(env.angle if is_angle else env.position),
        "q_des": _sym(env.angle if is_angle else env.position),
        "qdot": _sym(env.angle_rate if is_angle else env.position_rate),
        "qdot_des": _sym(env.angle_rate if is_angle else env.position_rate),
        "tau": _sym(env.torque),
        "u_prev": _sym(env.torque),
        "e": _sym(env.error),
        "edot": _sym(env.error_rate),
        "qddot_des": _sym(env.accel_des),
        "k1": env.gain,
        "k2": env.gain,
        "H1hat": _sym(env.h1hat),
        "omega": _sym(env.h1hat),
        "newer": _sym(env.h1hat),
        "older": _sym(env.h1hat),
        "gain": env.adaptive_gain,
        "eps": env.eps,
        "span": env.span,
        "trig": (-1.0, 1.0),
        "trig_prev": (-1.0, 1.0),
        "minv_norm": env.norm,
        "dn_new": env.norm,
        "dn_kept": env.norm,
        "w": (0.0, 1.0),
        "longitudinal": _sym(env.force),
        "lateral": _sym(env.force),
        "mu": env.mu,
        "loads": env.load,
        "shares": (0.0, 1.0),
        "integral": _sym(env.integral),
    }
    rates = {"qdot_now", "qdot_then", "wheel_rates"}
    if arg in rates:  # wheel rates (minimal form) or full rates
        return _sym(env.angle_rate if (is_angle or arg == "wheel_rates") else
                    env.position_rate)
    if arg in table:
        return table[arg]
    if arg == "gains" and len(angles) == 0:  # lyapunov_p: k1, k2, q1, q2
        return env.gain if index < 2 else env.weight
    if arg == "gains":
        return env.pi_gains[index]
    if arg == "bounds":
        return env.alpha if index == 0 else env.phi
    if arg == "adapt":
        return env.gamma if index == 0 else env.h
    if arg == "limits":
        return env.h if index == 0 else (1.0, env.torque)
    if arg == "payload":
        return env.payload_mass if index == 0 else _sym(env.payload_offset)
    if arg == "phys" and f"phys[{index}]" in params:  # plant_params_from_physical's inputs
        return params[f"phys[{index}]"]
    if arg == "x":  # the plant's state: q's pose, then the wheel rates
        return _sym(env.angle_rate) if index >= 3 else input_range(
            f"q[{index}]", angles, params, derived, env)
    raise BoxError(f"no declared range for input {access}")


def box_of(program: Program, angles: Sequence[bool], params: Mapping[str, Interval],
           derived: Mapping[str, Interval], env: Envelope = ENVELOPE
           ) -> dict[sp.Symbol, Interval]:
    """The declared box of ``program``'s inputs."""
    lyapunov = program.function == "lyapunov_p"
    return {s: input_range(a, () if lyapunov and a.startswith("gains") else angles,
                           params, derived, env)
            for s, a in program.input_names.items()}


def input_errors(program: Program) -> dict[sp.Symbol, float]:
    """Inputs that arrive already rounded in float32 with a known error: sin and cos from
    ``wmr_sincos_checked`` (2 ulp of a value within [-1, 1])."""
    return {s: 2.0 * 2.0 * U for s, a in program.input_names.items()
            if a.startswith(("trig[", "trig_prev["))}
