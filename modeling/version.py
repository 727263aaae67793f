"""The toolchain's version: the package's (pyproject reads it from here) and the one every
generated file's preamble records, so a file says which toolchain wrote it."""

VERSION = "0.2.0"
