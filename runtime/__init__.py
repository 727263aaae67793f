"""The simulation runtime: runs generated robot code (cffi, NumPy) in closed loop.

Top level, generic (any generated robot): ``cbuild`` (C build and binding),
``generated_modules`` and ``robot_source`` (which generated code and robot file),
``experiment`` (experiment files), ``robot_*`` and ``closed_loop`` (the experiment scaled
to a robot), ``reproduce_command`` (``python -m runtime reproduce``). ``paper``: the
paper's experiments and analyses on its differential drive. ``tooling``: measuring and
documenting the generated code.
"""
