"""A command's robot and its experiment scaled to it: the floor above the bindings.

* :mod:`~runtime.setting.scale`: a robot's size measured on its generated code, and an
  experiment scaled to it (the same way for every command);
* :mod:`~runtime.setting.layout`: the robot's bodies and wheels as an engine builds them,
  and the traction-aware torque limit;
* :mod:`~runtime.setting.robot`: the robot a command runs (resolved from a file, a folder
  or a name) with the experiment scaled to it, a :class:`~runtime.setting.robot.Setting`.

No imports here: each module is imported on its own.
"""
