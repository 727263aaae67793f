"""Tools that measure and document the generated code — benchmarks, firmware size/stack
reports, the bad-input table, the C-vs-Python cross-check — as opposed to the simulation
runtime (``runtime`` for any generated robot, ``runtime.paper`` for the paper's robot).
"""
