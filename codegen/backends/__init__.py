"""One package per target language: ``c``, ``python``, ``casadi``."""
