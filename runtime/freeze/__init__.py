"""``wmr freeze``: a controller configuration validated by the generated C and compiled
into firmware.

* :mod:`~runtime.freeze.header`: the configuration and the state ``_init`` derives from it,
  rendered as ``<prefix>_<ctrl>_frozen.h``;
* :mod:`~runtime.commands.freeze`: the command line (the robot, the experiment, the
  configuration's fields, the sampled-data verdict).

No imports here: each module is imported on its own.
"""
