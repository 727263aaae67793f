"""The one closed loop, for every robot and every command.

* :mod:`~runtime.sim.plant`: the :class:`~runtime.sim.plant.Plant` protocol and the
  generated-model plant (RK4 in C, generic over robots);
* :mod:`~runtime.sim.sensors`: encoders, rate models, odometry over every other coordinate;
* :mod:`~runtime.sim.reference` and :mod:`~runtime.sim.paths`: references that satisfy the
  constraints, and the paper's circle and lawn mower for any robot;
* :mod:`~runtime.sim.payload`: the payload schedule as true parameters;
* :mod:`~runtime.sim.faults`: sensor and actuator faults;
* :mod:`~runtime.sim.loop`: ``run``, one controller on one reference, a ``Run`` record;
* :mod:`~runtime.sim.outcome`: whether a run is ``ok``, said the same way everywhere.

No imports here: each module is imported on its own.
"""
