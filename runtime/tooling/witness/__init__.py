"""The witness: the paper's equations typed by hand (NumPy), independent of modeling/ and
codegen/.

``model``: (9), (6)–(8), (13), (14), (31) and the minimal form SᵀMS; ``controllers``:
TDC, TDROC, ROC, ASMC; ``wheel_pi``: the wheel-rate PI. Used by ``runtime.tooling.crosscheck``
as the reference that every generated implementation is compared with, and timed by
``runtime.tooling.bench`` (with ``csrc/hand_model.c``). ``csrc/fuzz_driver.c`` drives the
``wmr_`` controllers under sanitizers (tests/firmware/test_firmware_sanitizers.py).
"""

# Every controller of the registry (``modeling.controllers.REGISTRY``, read, not imported)
# and its witness here: the hand-typed law, and the check that compares the generated code
# with it. tests/generated/test_witness_registry.py fails for a registered controller in
# neither table, and for an entry naming no registered controller or no witness.
WITNESSES: dict[str, tuple[str, str, str]] = {
    # name: (witness module, its object, the check that compares the generated code with it)
    "tdc": ("runtime.tooling.witness.controllers", "KINDS",
            "runtime.tooling.crosscheck (tests/generated/test_crosscheck.py)"),
    "tdroc": ("runtime.tooling.witness.controllers", "KINDS",
              "runtime.tooling.crosscheck (tests/generated/test_crosscheck.py)"),
    "roc": ("runtime.tooling.witness.controllers", "KINDS",
            "runtime.tooling.crosscheck (tests/generated/test_crosscheck.py)"),
    "asmc": ("runtime.tooling.witness.controllers", "KINDS",
             "runtime.tooling.crosscheck (tests/generated/test_crosscheck.py)"),
    "pi": ("runtime.tooling.witness.wheel_pi", "WheelPI",
           "tests/generated/test_generated_controllers.py::"
           "test_wheel_pi_matches_the_hand_written_witness"),
}

# A registered controller with no witness, and why (the one place such a reason is kept).
EXEMPT: dict[str, str] = {}
