"""The run-time check of a robust step's float32 certificate conditions (issue 50).

The TDROC and ASMC steps' torque bounds (:mod:`.steps`) hold only while quantities the
step itself produces stay in the boxes the law's and (25)'s gain function's certificates
are stated over: the law's switching gain (TDROC: k-hat of (25); ASMC: the adapted gain
the state carries) in its gain box, and (25)'s inputs, ||M-hat^-1|| and the window's
difference norms ||Omega(i) - Omega(i+1)||, in the gain function's. Nothing in a step
checks them (k-hat and the adapted gain are capped at GAIN_MAX only), and a check there
would slow every step; so each such controller gets a function that reads its state
after a step and says whether that step's inputs were in those boxes
(``<prefix>_<controller>_within_certificate``). Its thresholds are the boxes the certifier
itself reads (:func:`~codegen.backends.c.certify.boxes.input_range` of the inputs
``gain``, ``minv_norm``, ``dn_new`` and ``dn_kept``): one declaration, never a second
literal. The generated C (``controller.{h,c}.jinja``) and the Python mirror render
:func:`gate_of`'s numbers.
"""

from __future__ import annotations

from dataclasses import dataclass

from codegen.backends.c.certify.boxes import ENVELOPE, Envelope, Interval, input_range
from codegen.certify.runtime_check import check_function, has_check
from modeling.controllers import ControllerSpec


@dataclass(frozen=True)
class Gate:
    """The boxes a robust step's certified torque bound is conditional on."""

    gain: Interval  # the law's switching gain (k-hat; ASMC's adapted gain)
    norm: Interval | None  # ||M-hat^-1||, (25)'s input (None: no window gain)
    window: Interval | None  # each difference norm (25) reads (None: no window gain)


def _declared(access: str, env: Envelope) -> Interval:
    # no angles, parameters or derived inputs: these inputs' boxes depend on none of them
    return input_range(access, (), {}, {}, env)


def gate_of(info: ControllerSpec, env: Envelope = ENVELOPE) -> Gate | None:
    """The conditions of ``info``'s step (None: its bound has none to check at run time):
    a window gain (25) (TDROC) checks its gain, ||M-hat^-1|| and window; an adapted gain
    (ASMC) its gain. These are the steps whose certificates :mod:`.steps` states "if ..."
    for (the gain: ``arg == "gain"`` with a window gain or an adapted one)."""
    if not has_check(info):
        return None
    gain = _declared("gain[0]", env)
    if not info.window:
        return Gate(gain, None, None)
    window = _declared("dn_new[0]", env)
    if _declared("dn_kept[0]", env) != window:  # (25) reads the newest and the kept alike
        raise ValueError("the certifier declares different boxes for dn_new and dn_kept: "
                         "the run-time check tests one box for the whole window")
    return Gate(gain, _declared("minv_norm[0]", env), window)


def gate_context(info: ControllerSpec, prefix: str) -> dict[str, object] | None:
    """:func:`gate_of` for the templates (the C controller's header and source, the Python
    mirror): the function's name and each box's ends as literals that C and Python read
    alike (``repr`` of a float: the certifier's double exactly); None without a check."""
    gate = gate_of(info)
    if gate is None:
        return None

    def ends(box: Interval | None) -> tuple[str, str] | None:
        return None if box is None else (repr(float(box[0])), repr(float(box[1])))

    return {"function": check_function(prefix, info.name), "gain": ends(gate.gain),
            "norm": ends(gate.norm), "window": ends(gate.window)}
