"""The paper's experiment run on a robot (``wmr reproduce``): the runs and their numbers.

* :mod:`~runtime.reproduction.runs`: one run of the reproduction, refused the same way for
  every robot when the toolchain predicts the configuration fails (the configuration
  checks of :mod:`runtime.stability.checks`);
* :mod:`~runtime.reproduction.paper`: the paper's robot, Drishti: the runs, their metrics
  and TDROC's ε sweep, from which :mod:`runtime.paper` writes the report and figures;
* :mod:`~runtime.reproduction.robot`: any other robot, the experiment scaled to it, with
  its report.

No imports here: each module is imported on its own.
"""
