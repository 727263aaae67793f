"""The shipped robots, one folder each: ``modeling/robots/<name>/<name>.toml`` is the robot
file ``python -m codegen`` generates (``modeling.robot_file.shipped_robot_files``), and
whatever else belongs to that robot alone sits beside it.

``drishti/``  the paper's robot (Roy et al. 2017): its robot file, its hand-typed
              Lagrangian model, its body/wheel description, the paper's printed equations
              with a verdict on each, and its ``MODEL.md`` report (a Python package)
``trailer/``  a differential drive towing a passive cart: a ``[[body]]`` robot file only;
              everything about it is derived by the generic ``modeling.description``

The generic machinery (``modeling.lagrange``, ``modeling.description``,
``modeling.robot_model``, ``codegen``) does not import a robot from here. The exceptions
name the default robot, Drishti: ``modeling.robot_file``, whose table of robot kinds sends a
``[lumped]``/``[physical]`` file to Drishti's model with other numbers (read by
``drishti/robot_file.py``; named after its own file, not Drishti), the shipped-robot table
of ``modeling.robot_io`` (Drishti's own file: prefix ``wmr``, the root of ``generated/``,
the paper's robot), and the transitional default of ``modeling.controllers``.
"""
