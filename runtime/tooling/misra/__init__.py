"""MISRA C:2012 check of the generated C with cppcheck's MISRA addon (``check``), against the
deviations documented in ``docs/STATIC_CHECKS.md``."""
