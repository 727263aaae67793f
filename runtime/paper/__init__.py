"""The paper's reproduction (Roy et al. 2017, Section 5): the paper's experiment on its
robot, Drishti, run on the one closed loop of ``runtime.sim``, and what it is compared with.

``reproduce`` (the runs, their metrics and TDROC's ε sweep) with ``reproduction_tables``,
``reproduction_verdicts`` (the paper's claims and the stability bounds), ``reproduction_report``
and ``figures`` (its metrics, report and figures), ``printed_paths`` (the paper's printed,
inconsistent path definitions, drawn beside ours), and ``handwritten`` (the paper's
equations typed by hand, the independent witness of the cross-check and the benchmarks,
with ``csrc/hand_model.c``). ``csrc/fuzz_driver.c`` drives the ``wmr_`` controllers under
sanitizers (tests/firmware/test_firmware_sanitizers.py).

No imports here: each module is imported on its own.
"""
