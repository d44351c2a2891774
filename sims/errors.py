"""Errors of the simulators (defined with the project's one base in `tailor.errors`)."""

from tailor.errors import SimError  # noqa: F401
