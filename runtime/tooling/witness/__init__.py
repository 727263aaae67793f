"""The witness: the paper's equations typed by hand (NumPy), independent of modeling/ and
codegen/.

``model``: (9), (6)–(8), (13), (14), (31) and the minimal form SᵀMS; ``controllers``:
TDC, TDROC, ROC, ASMC; ``wheel_pi``: the wheel-rate PI. Used by ``runtime.tooling.crosscheck``
as the reference that every generated implementation is compared with, and timed by
``runtime.tooling.bench`` (with ``csrc/hand_model.c``). ``csrc/fuzz_driver.c`` drives the
``wmr_`` controllers under sanitizers (tests/firmware/test_firmware_sanitizers.py).
"""
