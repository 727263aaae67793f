"""The paper's reproduction (Roy et al. 2017, Section 5) written out: the report, tables,
verdicts and figures of the runs the one driver,
:mod:`runtime.reproduction.driver`, made on its robot, Drishti.

``reproduction_tables``, ``reproduction_verdicts`` (the paper's claims and the stability
bounds), ``reproduction_report`` and ``figures`` (its metrics, report and figures), and
``printed_paths`` (the paper's printed, inconsistent path definitions, drawn beside ours).
The hand-written witness of the paper's equations is ``runtime.tooling.witness``.

No imports here: each module is imported on its own.
"""
