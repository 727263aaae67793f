"""Experiments as data: what is run on a robot (the runtime's lowest floor: it imports no
other runtime package).

* :mod:`~runtime.experiment.settings`: experiment files (TOML), every field checked; the
  defaults are the paper's setting, written for :data:`~runtime.experiment.settings.PAPER_ROBOT`;
* :mod:`~runtime.experiment.faults`: the sensor and actuator faults an experiment injects
  (its ``[[fault]]`` tables) and their per-sample schedule.

The experiment scaled to a robot is :mod:`runtime.setting`; its runs are
:mod:`runtime.reproduction`.

No imports here: each module is imported on its own.
"""
