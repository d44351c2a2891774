"""Errors of the simulators (sims never imports refinement, so it has its own base class)."""

from __future__ import annotations


class SimError(Exception):
    """Invalid simulator input: an unknown action, a state or parameter outside the world."""

    exit_code = 15

    def __init__(self, message: str, file: str | None = None):
        super().__init__(message)
        self.message = message
        self.file = file

    def __str__(self) -> str:
        return f"{self.file}: {self.message}" if self.file else self.message
