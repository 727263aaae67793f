"""Tools that measure and document the generated code — the hand-written witness
(``witness``) and the C-vs-Python cross-check (``crosscheck``), the fuzz driver, benchmarks
(``bench``), firmware size/stack reports (``firmware``), the bad-input table, MISRA — as
opposed to the simulation runtime below them. The top floor of ``runtime``: it may import
any other floor, and none imports it.
"""
