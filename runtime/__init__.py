"""The runtime: what a user runs, on the generated code of any robot (NumPy, cffi, Dask).

Split by job, never by robot (DESIGN.md):

* ``bindings``: the one way to build, load and call a robot's generated code (cffi build,
  the controller wrapper, the configuration builder, ``--robot`` resolved);
* ``experiment``: experiment files, an experiment scaled to a robot, its reproduction on any
  robot;
* ``sim``: the one closed loop (plants, sensors, references and paths, faults, outcomes);
* ``stability``: the sampled-data verdicts and the configuration checks; ``campaign``;
  ``freeze``; ``fault_table`` (``wmr faults``); ``reproduce_command`` (``wmr reproduce``);
* ``paper``: the paper's reproduction only (an experiment of the Drishti robot), and the
  hand-written witness;
* ``tooling``: measuring and documenting the generated code.
"""
