"""Mutation check: realistic one-line bugs applied one at a time to a copy of the project,
each against the tests meant to catch it (``python -m runtime.tooling.mutation``)."""
