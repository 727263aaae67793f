"""The command line: every ``main`` and every ``argparse`` parser of the runtime's commands,
above the modules that do the work (``runtime.cli`` names them as strings).

* :mod:`~runtime.commands.options`: ``--robot``, ``--generated``, ``--experiment``,
  ``--plant`` as every command has them, and where a command writes by default;
* :mod:`~runtime.commands.output_folder`: an output folder checked before any work;
* one module per command: :mod:`~runtime.commands.reproduce`,
  :mod:`~runtime.commands.faults`, :mod:`~runtime.commands.stability`,
  :mod:`~runtime.commands.campaign`, :mod:`~runtime.commands.freeze`,
  :mod:`~runtime.commands.compare_plants`.

(``runtime.tooling``'s reports keep their own ``main``: tooling sits above everything.)

No imports here: each module is imported on its own.
"""
