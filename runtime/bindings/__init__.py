"""The one way from Python to a robot's generated code.

* :mod:`~runtime.bindings.cbuild`: compile a robot's generated C (with runtime C helpers)
  into a cached shared library and bind it with cffi, declarations read from the headers;
* :mod:`~runtime.bindings.generated`: a robot's generated NumPy modules and what its
  ``robot.py`` declares (sizes, parameters, the controllers of the registry);
* :mod:`~runtime.bindings.robots`: ``--robot`` of every command (a robot file, a generated
  folder or a generated robot's name) resolved to code and parameters;
* :mod:`~runtime.bindings.controller`: one controller instance of the generated C
  (init, step, reset, state, statuses by name);
* :mod:`~runtime.bindings.config`: the controller configuration from the registry's field
  sources, an experiment and the nominal parameters;
* :mod:`~runtime.bindings.uncertainty`: the nominal model against the robots of an
  uncertainty box (the TDE condition of (17), ROC's α and φ).

No imports here: each module is imported on its own.
"""
