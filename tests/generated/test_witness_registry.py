"""Every registered controller has an independent witness, or a reason why not, in one place
(issue 46): ``runtime.tooling.witness.WITNESSES`` / ``EXEMPT`` against
``modeling.controllers.REGISTRY``. A controller added to the registry alone fails here, so
it is never silently left out of the hand-written comparison."""

from __future__ import annotations

import dataclasses
import importlib
import inspect
from collections.abc import Sequence

from modeling.controllers import REGISTRY, ControllerSpec
from runtime.tooling import witness
from runtime.tooling.witness import controllers as hand


def missing_witnesses(registry: Sequence[ControllerSpec]) -> list[str]:
    """One line per problem: a controller in neither table, in both, an exemption without
    a reason, an entry naming no registered controller, or a witness that does not exist
    (a law kind of the hand-typed controllers must be one of their ``KINDS``)."""
    names = {c.name for c in registry}
    out = []
    for name in sorted(names):
        if (name in witness.WITNESSES) == (name in witness.EXEMPT):
            out.append(f"{name}: needs a witness (WITNESSES) or a reasoned exemption "
                       "(EXEMPT), exactly one")
        elif name in witness.EXEMPT and len(witness.EXEMPT[name].split()) < 4:
            out.append(f"{name}: the exemption needs a reason, got {witness.EXEMPT[name]!r}")
    for name in sorted({*witness.WITNESSES, *witness.EXEMPT} - names):
        out.append(f"{name}: listed, but no such controller is registered")
    for name, (module, obj, check) in witness.WITNESSES.items():
        found = getattr(importlib.import_module(module), obj, None)
        if found is None:
            out.append(f"{name}: {module}.{obj} does not exist")
        elif obj == "KINDS" and name not in found:
            out.append(f"{name}: not one of the hand-typed laws {found}")
        elif obj != "KINDS" and not inspect.isclass(found):
            out.append(f"{name}: {module}.{obj} is not a hand-typed controller")
        if not check:
            out.append(f"{name}: no check named that compares the generated code with it")
    return out


def test_every_registered_controller_has_a_witness() -> None:
    assert missing_witnesses(REGISTRY) == []


def test_the_check_fails_for_a_controller_added_alone() -> None:
    """A sixth controller registered without a witness is reported (the check can fail)."""
    toy = dataclasses.replace(REGISTRY[0], name="pd")
    assert missing_witnesses((*REGISTRY, toy)) == [
        "pd: needs a witness (WITNESSES) or a reasoned exemption (EXEMPT), exactly one"]


def test_the_hand_typed_laws_are_all_listed() -> None:
    """Each law the witness types by hand is the witness of a registered controller."""
    assert set(hand.KINDS) <= set(witness.WITNESSES)
