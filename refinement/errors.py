"""Errors of the refinement stage; like the planner bridge's, each is one line naming the file and the problem."""

from __future__ import annotations

from planner_bridge.errors import PlannerError


class TailorError(PlannerError):
    """Base of refinement, learning and command-line errors (a PlannerError so the CLI treats all alike)."""

    exit_code = 9


class BeliefError(TailorError):
    """A belief-state file is missing or invalid."""

    exit_code = 10


class BindingError(TailorError):
    """An action library binding is missing or invalid, or a plan uses an action it does not bind."""

    exit_code = 11


class ModelFileError(TailorError):
    """An action model file is missing, of the wrong schema, or inconsistent."""

    exit_code = 12


class EmptyRangeError(TailorError):
    """The ranges the predicates imply for a parameter do not intersect (or a bound value lies outside them)."""

    exit_code = 13


class DataError(TailorError):
    """Experience data is missing or malformed."""

    exit_code = 14
