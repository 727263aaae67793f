"""``python -m runtime <command>``: the same commands as the ``wmr`` console script
(:mod:`runtime.cli`)."""

from __future__ import annotations

import sys

from runtime.cli import main

if __name__ == "__main__":
    sys.exit(main(prog="python -m runtime"))
