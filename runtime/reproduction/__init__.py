"""The paper's experiment run on a robot (``wmr reproduce``): the runs and their numbers.

* :mod:`~runtime.reproduction.runs`: one run of the reproduction, refused the same way for
  every robot when the toolchain predicts the configuration fails (the configuration
  checks of :mod:`runtime.stability.checks`);
* :mod:`~runtime.reproduction.driver`: the one driver, for every robot: the runs, their
  metrics and outcomes, and on the paper's robot (a setting: ``Setting.is_paper_robot``)
  TDROC's ε sweep, from which :mod:`runtime.paper` writes the paper's report and figures;
* :mod:`~runtime.reproduction.robot_report`: the report of any other robot.

No imports here: each module is imported on its own.
"""
