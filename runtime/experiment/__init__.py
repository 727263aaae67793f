"""Experiments: what is run on a robot, and the paper's setting scaled to any robot.

* :mod:`~runtime.experiment.settings`: experiment files (TOML), every field checked; the
  defaults are the paper's setting, written for :data:`~runtime.experiment.settings.PAPER_ROBOT`;
* :mod:`~runtime.experiment.scale`: a robot's size measured on its generated code, and an
  experiment scaled to it (the same way for every command);
* :mod:`~runtime.experiment.reproduction`: an experiment's runs on any robot, their metrics
  and report (``wmr reproduce --robot``).

No imports here: each module is imported on its own.
"""
