"""Whether a controller configuration is stable on a robot, and the checks that refuse one.

* :mod:`~runtime.stability.sampled_loop`: the sampled closed loop of any generated robot
  linearised about a steady motion (delay included), its pencil J(g) = J₀ + g J₁ in the
  boundary-layer gain, the largest tolerated delay;
* :mod:`~runtime.stability.analysis`: verdicts per controller and formulation, k̂ measured
  in closed loop, the tables of ``wmr stability`` (:mod:`runtime.commands.stability`), and
  the verdict of a filled configuration (``wmr freeze``);
* :mod:`~runtime.stability.saturation`: the torque and wind-up verdict, predicted along the
  paths and simulated;
* :mod:`~runtime.stability.verification`: the predicted boundary checked by simulation;
* :mod:`~runtime.stability.checks`: what a configuration must pass before it is run (the
  TDE condition over the uncertainty box, the sampled loop), called by the reproduction.

No imports here: each module is imported on its own.
"""
