"""The runtime: what a user runs, on the generated code of any robot (NumPy, cffi, Dask).

Split by job, never by robot, and built on floors: each sub-package (or top-level module)
imports only from the floors below it, never from its own floor's neighbours, never upwards,
not even inside a function (``tests/structure/test_import_structure.py``, ``RUNTIME_FLOORS``). From
the bottom:

1. ``experiment``: experiment files and the faults they inject (data);
2. ``bindings``: the one way to build, load, configure and call a robot's generated code,
   and ``--robot`` resolved;
3. ``setting``: a robot's size, its layout, and the experiment scaled to it;
4. ``sim``: the one closed loop (sensors, references and paths, payload, outcomes) and the
   generated-model plant; it runs any configuration it is given;
5. ``mujoco``: the other plant;
6. ``plants``: the plant registry, above every plant;
7. ``stability``: the sampled-data verdicts and the configuration checks;
8. ``reproduction`` (one checked run for every robot; the paper's robot and any other),
   ``fault_table`` and ``plant_comparison``: the drivers;
9. ``paper`` (the reproduction's report, tables and figures, and the hand-written
   witness), ``campaign``, ``freeze``;
10. ``commands``: every ``main`` and ``argparse`` parser; ``cli`` (``wmr``, naming the
    commands as strings) and ``__main__`` above them;
11. ``tooling``: measuring and documenting the generated code (cross-check, fuzz driver,
    bench, firmware), above everything.
"""
