"""The run-time check of a robust step's float32 certificate conditions (issue 50).

The TDROC and ASMC steps' torque bounds (``codegen.backends.c.certify.steps``) hold only
while quantities the step itself produces stay in the boxes the law's and (25)'s gain
function's certificates are stated over: the law's switching gain (TDROC: k-hat of (25);
ASMC: the adapted gain the state carries) in its gain box, and (25)'s inputs,
||M-hat^-1|| and the window's difference norms ||Omega(i) - Omega(i+1)||, in the gain
function's. Nothing in a step checks them (k-hat and the adapted gain are capped at
GAIN_MAX only), and a check there would slow every step; so each such controller gets a
function that reads its state after a step and says whether that step's inputs were in
those boxes (``<prefix>_<controller>_within_certificate``, and the Python mirror's
``within_certificate``). Its thresholds are the certifier's envelope
(:mod:`codegen.certify.envelope`), the fields the certifier's boxes read for those inputs
(``codegen.backends.c.certify.gate`` checks that ``boxes.input_range`` gives the same
boxes before the C is rendered): one declaration, never a second literal. Imports no
backend, so every backend and the reports may import it.
"""

from __future__ import annotations

from dataclasses import dataclass

from codegen.certify.envelope import ENVELOPE, Envelope, Interval
from modeling.controllers import ControllerSpec
from modeling.controllers.registry import controller as registered

# The certifier's inputs (``boxes.input_range``'s names) whose boxes the check tests, and
# the envelope field each is declared by.
CHECKED_INPUTS: dict[str, str] = {"gain": "adaptive_gain", "minv_norm": "norm",
                                  "dn_new": "norm", "dn_kept": "norm"}


@dataclass(frozen=True)
class Gate:
    """The boxes a robust step's certified torque bound is conditional on."""

    gain: Interval  # the law's switching gain (k-hat; ASMC's adapted gain)
    norm: Interval | None  # ||M-hat^-1||, (25)'s input (None: no window gain)
    window: Interval | None  # each difference norm (25) reads (None: no window gain)


def has_check(info: ControllerSpec) -> bool:
    """A step whose torque bound is conditional on what the step produces: (25)'s window
    gain (TDROC) or a gain the law adapts (ASMC), the steps whose certificates
    ``steps.py`` states "if ..." for."""
    return bool(info.window or info.adaptive)


def declared(arg: str, env: Envelope = ENVELOPE) -> Interval:
    """The envelope's box of the certifier's input ``arg`` (one of :data:`CHECKED_INPUTS`)."""
    box: Interval = getattr(env, CHECKED_INPUTS[arg])
    return box


def gate_of(info: ControllerSpec, env: Envelope = ENVELOPE) -> Gate | None:
    """The conditions of ``info``'s step (None: its bound has none to check at run time):
    a window gain (25) (TDROC) checks its gain, ||M-hat^-1|| and window; an adapted gain
    (ASMC) its gain."""
    if not has_check(info):
        return None
    gain = declared("gain", env)
    if not info.window:
        return Gate(gain, None, None)
    window = declared("dn_new", env)
    if declared("dn_kept", env) != window:  # (25) reads the newest and the kept alike
        raise ValueError("the envelope declares different boxes for dn_new and dn_kept: "
                         "the run-time check tests one box for the whole window")
    return Gate(gain, declared("minv_norm", env), window)


def check_function(prefix: str, controller: str) -> str:
    """The C function that checks a step's conditions."""
    return f"{prefix}_{controller}_within_certificate"


def gate_context(info: ControllerSpec, prefix: str,
                 env: Envelope = ENVELOPE) -> dict[str, object] | None:
    """:func:`gate_of` for the templates (the C controller's header and source, the Python
    mirror): the function's name and each box's ends as literals that C and Python read
    alike (``repr`` of a float: the envelope's double exactly); None without a check."""
    gate = gate_of(info, env)
    if gate is None:
        return None

    def ends(box: Interval | None) -> tuple[str, str] | None:
        return None if box is None else (repr(float(box[0])), repr(float(box[1])))

    return {"function": check_function(prefix, info.name), "gain": ends(gate.gain),
            "norm": ends(gate.norm), "window": ends(gate.window)}


def checked_by(prefix: str, controller: str) -> str:
    """The note a step row of the reports gets for a controller with a check, else ""."""
    return (f"run-time check: `{check_function(prefix, controller)}`, called after the step"
            if has_check(registered(controller)) else "")
