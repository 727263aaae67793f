"""The run-time check of the robust steps' certificate conditions takes its boxes from the
certifier's envelope (codegen/certify/envelope.py), and the C backend refuses to render it
when those are not the boxes the certifier gives the certified inputs (boxes.input_range):
the check can never test other boxes than the certified ones."""

from __future__ import annotations

import dataclasses

import pytest

from codegen.backends.c.certify import gate
from codegen.backends.c.certify.boxes import ENVELOPE, input_range
from codegen.certify import runtime_check
from modeling.controllers import REGISTRY

INFO = {c.name: c for c in REGISTRY}


def test_the_checked_controllers_and_their_boxes_are_the_certifiers() -> None:
    assert {c.name for c in REGISTRY if runtime_check.has_check(c)} == {"tdroc", "asmc"}
    tdroc = runtime_check.gate_of(INFO["tdroc"])
    asmc = runtime_check.gate_of(INFO["asmc"])
    assert runtime_check.gate_of(INFO["roc"]) is None
    assert tdroc is not None and asmc is not None
    assert tdroc.gain == asmc.gain == input_range("gain[0]", (), {}, {}) == (0.0, 100.0)
    assert tdroc.norm == input_range("minv_norm[0]", (), {}, {}) == (0.0, 10.0)
    assert tdroc.window == input_range("dn_kept[3]", (), {}, {}) == (0.0, 10.0)
    assert asmc.norm is None and asmc.window is None
    ctx = gate.certified_gate_context(INFO["tdroc"], "wmr")
    assert ctx == {"function": "wmr_tdroc_within_certificate", "gain": ("0.0", "100.0"),
                   "norm": ("0.0", "10.0"), "window": ("0.0", "10.0")}


def test_a_check_box_other_than_the_certifiers_is_refused(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # the check reading another envelope field for the gain than the certifier does
    monkeypatch.setitem(runtime_check.CHECKED_INPUTS, "gain", "gain")
    with pytest.raises(ValueError, match="box of gain"):
        gate.certified_gate_context(INFO["asmc"], "wmr")


def test_one_declaration_moves_both() -> None:
    wider = dataclasses.replace(ENVELOPE, adaptive_gain=(0.0, 250.0))
    assert input_range("gain[0]", (), {}, {}, wider) == (0.0, 250.0)
    g = runtime_check.gate_of(INFO["tdroc"], wider)
    assert g is not None and g.gain == (0.0, 250.0)
    ctx = gate.certified_gate_context(INFO["tdroc"], "wmr", wider)
    assert ctx is not None and ctx["gain"] == ("0.0", "250.0")
