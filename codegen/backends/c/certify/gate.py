"""The run-time check's boxes as the certifier has them: before the C of a robust step's
``<prefix>_<controller>_within_certificate`` is rendered, the boxes
:mod:`codegen.certify.runtime_check` takes from the envelope must be those
:func:`~codegen.backends.c.certify.boxes.input_range` gives the certified functions'
inputs (the law's ``gain``; ``tdroc_weighted_gain``'s ``minv_norm``, ``dn_new``,
``dn_kept``): a change to either mapping refuses to generate instead of checking other
boxes than the certified ones.
"""

from __future__ import annotations

from codegen.backends.c.certify.boxes import ENVELOPE, Envelope, input_range
from codegen.certify.runtime_check import CHECKED_INPUTS, declared, gate_context
from modeling.controllers import ControllerSpec


def certified_gate_context(info: ControllerSpec, prefix: str,
                           env: Envelope = ENVELOPE) -> dict[str, object] | None:
    """:func:`~codegen.certify.runtime_check.gate_context`, after checking its boxes against
    the certifier's (raises ``ValueError`` naming the input that differs)."""
    for arg in CHECKED_INPUTS:
        # these inputs' boxes depend on no angle, parameter or derived input
        certified = input_range(f"{arg}[0]", (), {}, {}, env)
        if certified != declared(arg, env):
            raise ValueError(f"the run-time check's box of {arg}, {declared(arg, env)}, is not "
                             f"the certifier's, {certified}")
    return gate_context(info, prefix, env)
