"""The one closed loop, for every robot and every command.

* :mod:`~runtime.sim.plant`: the :class:`~runtime.sim.plant.Plant` protocol and the
  generated-model plant (RK4 in C, generic over robots); which plant a run gets is the
  registry's, :mod:`runtime.plants`, above every plant;
* :mod:`~runtime.sim.sensors`: encoders, rate models, odometry over every other coordinate;
* :mod:`~runtime.sim.reference` and :mod:`~runtime.sim.paths`: references that satisfy the
  constraints, and the paper's circle and lawn mower for any robot;
* :mod:`~runtime.sim.payload`: the payload schedule as true parameters;
* the faults the loop injects are the experiment's (:mod:`runtime.experiment.faults`);
* :mod:`~runtime.sim.slip_monitor`: the friction each wheel's contact needs (a plant wrapper);
* :mod:`~runtime.sim.loop`: ``run``, one controller on one reference, a ``Run`` record
  (it runs any configuration: the checks that refuse one are the caller's);
* :mod:`~runtime.sim.outcome`: whether a run is ``ok``, said the same way everywhere.

No imports here: each module is imported on its own.
"""
