"""Errors of refinement, learning and the command line (defined with the project's one base in `tailor.errors`)."""

from tailor.errors import (  # noqa: F401
    BeliefError,
    BindingError,
    DataError,
    EmptyRangeError,
    ModelFileError,
    OutputFileError,
    SimError,
    TailorError,
)
