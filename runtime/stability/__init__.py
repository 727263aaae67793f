"""Whether a controller configuration is stable on a robot, and the checks that refuse one.

* :mod:`~runtime.stability.sampled_loop`: the sampled closed loop linearised, its pencil
  J(g) = J₀ + g J₁ in the boundary-layer gain (written for the paper's differential drive:
  Drishti and every ``[lumped]``/``[physical]`` robot);
* :mod:`~runtime.stability.analysis`: verdicts per controller and formulation, k̂ measured
  in closed loop, ``wmr stability``, and the verdict of a filled configuration (``wmr freeze``);
* :mod:`~runtime.stability.verification`: the predicted boundary checked by simulation;
* :mod:`~runtime.stability.checks`: what a configuration must pass before it is run with
  ``check=True`` (the TDE condition over the uncertainty box, the sampled loop).

No imports here: each module is imported on its own.
"""
