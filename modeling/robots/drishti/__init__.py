"""Drishti, the robot of Roy et al. (2017), and everything that is about it alone.

``drishti.toml``          its robot file: the lumped parameters the paper prints
``parameters.py``         its parameter table (key, meaning, unit, C spelling, declared once)
                          and the ``[lumped]``/``[physical]`` robot-file format (no SymPy)
``robot_file.py``         such a file as a ``Robot`` (``[physical]`` → lumped through the
                          derived relations)
``model.py``              its hand-typed Lagrangian instance of ``modeling.lagrange`` (bodies,
                          kinetic energy, rolling constraints, inputs) and ``robot_model()``,
                          the ``RobotModel`` the generic code generator reads
``description.py``        the same robot as one body and two wheels
                          (``modeling.description``), to cross-check the two derivations
``paper/``                the paper's printed equations, transcribed, and a verdict on each
``report.py``             its ``MODEL.md`` (derivation and verdicts), rendered with
``model_report.md.jinja`` (named in ``robot_model().docs["report"]``)
"""
