"""Progress bars of long steps inside the library (the genetic algorithm, a refinement's windows), shown only
where a command asks for them and only on a terminal.

The same functions run thousands of times inside `tailor evaluate` and `tailor train` (in worker processes,
under their own bars), where a bar per call would be noise; so they are off unless the caller opens a
`showing_progress()` block, as `tailor refine` does. Bars go to stderr (tqdm's `disable=None`: none when stderr
is not a terminal).

The long runs of a command (gathering experience, training, evaluating) report with `stage_bar`: a bar on a
terminal; elsewhere (a log file, CI, a pipe) a log line when the stage starts, at least every LOG_EVERY_S while it
runs (also while one long step, a fit or a batch of episodes, keeps it from counting), and when it ends, so a run
that takes minutes never goes silent.
"""

from __future__ import annotations

import logging
import sys
import threading
import time
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


LOG_EVERY_S = 30.0  # off a terminal, a long stage says how far it is at least this often
log = logging.getLogger("tailor.progress")


class _LoggedStage:
    """A stage's progress as log lines (stderr is not a terminal): at the start, every LOG_EVERY_S, at the end.
    Between updates a watcher thread says how far it is once LOG_EVERY_S have passed without a line, so a step
    that takes minutes (one fit, one batch of episodes in the workers) does not silence the stage."""

    def __init__(self, total: int, desc: str, unit: str):
        self.total, self.desc, self.unit, self.n = total, desc, unit, 0
        self.started = self.said = time.monotonic()
        self._lock = threading.Lock()
        self._closed = threading.Event()
        log.info("%s: %d %s to do", desc, total, unit)
        self._watcher = threading.Thread(target=self._watch, name=f"progress: {desc}", daemon=True)
        self._watcher.start()

    def update(self, n: int = 1) -> None:
        with self._lock:
            self.n += n
            self._say(time.monotonic())

    def _say(self, now: float) -> None:
        """The progress line, when LOG_EVERY_S have passed since the last line (the lock held)."""
        if now - self.said >= LOG_EVERY_S and self.n < self.total:
            self.said = now
            log.info("%s: %d/%d %s (%.0f s)", self.desc, self.n, self.total, self.unit, now - self.started)

    def _watch(self) -> None:
        wait = LOG_EVERY_S
        while not self._closed.wait(max(wait, 0.01)):
            with self._lock:
                if self._closed.is_set():
                    return
                now = time.monotonic()
                self._say(now)
                wait = LOG_EVERY_S - (now - self.said)  # until the next line is due
                if wait <= 0:  # (done, not yet closed: no line is due)
                    wait = LOG_EVERY_S

    def set_postfix_str(self, *args, **kwargs) -> None:
        return None

    def close(self) -> None:
        if self._closed.is_set():
            return
        with self._lock:
            self._closed.set()
        if self.n >= self.total:
            log.info("%s: %d %s done in %.1f s", self.desc, self.n, self.unit, time.monotonic() - self.started)

    def __enter__(self) -> "_LoggedStage":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def stage_bar(total: int, desc: str, unit: str, enabled: bool = True):
    """The progress of one stage of a long command: a tqdm bar on a terminal, log lines elsewhere (_LoggedStage),
    nothing where `enabled` is False (-q) or there is nothing to do."""
    if not enabled or not total:
        return _NoBar()
    if sys.stderr is not None and sys.stderr.isatty():
        from tqdm import tqdm

        return tqdm(total=total, desc=desc, unit=unit, file=sys.stderr)
    return _LoggedStage(total, desc, unit)


def finish(bar) -> None:
    """Count a stage's bar as complete: a stage whose steps were fewer than the most it could take (training
    shares fits between the candidates it compares) still ends with its line saying it is done."""
    remaining = getattr(bar, "total", 0) - getattr(bar, "n", 0)
    if remaining > 0:
        bar.update(remaining)
