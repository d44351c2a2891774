"""Progress bars of long steps inside the library (the genetic algorithm, a refinement's windows), shown only
where a command asks for them and only on a terminal.

The same functions run thousands of times inside `tailor evaluate` and `tailor train` (in worker processes,
under their own bars), where a bar per call would be noise; so they are off unless the caller opens a
`showing_progress()` block, as `tailor refine` does. Bars go to stderr (tqdm's `disable=None`: none when stderr
is not a terminal).
"""

from __future__ import annotations

import sys
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar

_SHOWING: ContextVar[bool] = ContextVar("tailor_showing_progress", default=False)


@contextmanager
def showing_progress(enabled: bool = True) -> Iterator[None]:
    """Within this block (this thread or task), `progress_bar` shows bars on a terminal."""
    token = _SHOWING.set(enabled)
    try:
        yield
    finally:
        _SHOWING.reset(token)


class _NoBar:
    """What `progress_bar` gives where no bar is shown: no tqdm object at all, since tqdm's first instance in a
    process creates a multiprocessing lock (a semaphore), which a worker killed by SIGTERM would leak."""

    def __enter__(self) -> "_NoBar":
        return self

    def __exit__(self, *exc) -> None:
        return None

    def update(self, n: int = 1) -> None:
        return None

    def set_postfix_str(self, *args, **kwargs) -> None:
        return None

    def close(self) -> None:
        return None


def progress_bar(**kwargs):
    """A tqdm bar on stderr, shown on a terminal inside `showing_progress()`; elsewhere a stand-in that does
    nothing (the optimizers run thousands of times inside worker processes)."""
    if not _SHOWING.get():
        return kwargs["iterable"] if "iterable" in kwargs else _NoBar()
    from tqdm import tqdm

    return tqdm(file=sys.stderr, disable=None, **kwargs)
