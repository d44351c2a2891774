"""Where parallel work runs: the worker processes of a joblib backend (loky by default, or a Dask or Ray cluster).

A command opens one `backend_session(backend, jobs, scheduler)` around its work; inside it, `ordered_results`
runs independent calls in the session's workers and yields their results in the order of the calls, so the
output (episodes, fitted trees, evaluation rows) is the same for any backend and any number of workers: every
random step takes its seed from the call's arguments, never from the worker it lands on.

joblib's loky and Dask backends stream results (`return_as="generator"`); the multiprocessing and Ray backends
refuse it, and get the calls in waves of a few per worker (each wave a list, in order) so progress still moves.
"""

from __future__ import annotations

import contextlib
import logging
import signal
import threading
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

from tailor.errors import BackendError
from tailor.progress import stage_bar

BACKENDS = ("loky", "dask", "ray")
EXTRAS = {"dask": ("dask", "distributed"), "ray": ("ray",)}  # the packages each optional backend needs
WAVE_PER_WORKER = 4  # calls per worker in one wave, where the backend cannot stream results
CONNECT_SECONDS = 30  # how long joining an existing cluster may take


@dataclass(frozen=True)
class Session:
    """The backend in force: its joblib name, and the n_jobs joblib gets (-1: every worker of a cluster)."""

    backend: str
    n_jobs: int


_session: Session | None = None  # set by backend_session; None: loky with the caller's jobs


def missing_packages(backend: str) -> list[str]:
    """The optional packages `backend` needs that are not installed (none for loky)."""
    import importlib.util

    return [name for name in EXTRAS.get(backend, ()) if importlib.util.find_spec(name) is None]


@contextlib.contextmanager
def backend_session(backend: str = "loky", jobs: int = 1, scheduler: str | None = None) -> Iterator[Session]:
    """Run the enclosed parallel work on `backend`: loky processes on this machine (`jobs` of them), a Dask
    cluster (the one at `scheduler`, else a local one of `jobs` single-threaded worker processes) or a Ray
    cluster (at `scheduler`, else a local one of `jobs` CPUs). The cluster started here is stopped on leaving,
    also on Ctrl-C. A missing package or an unreachable scheduler is a BackendError."""
    global _session
    if backend not in BACKENDS:
        raise BackendError(f"unknown backend {backend!r}; known: {', '.join(BACKENDS)}")
    if backend == "loky" and scheduler:
        raise BackendError("--scheduler joins a Dask or Ray cluster: give --backend dask or ray with it")
    missing = missing_packages(backend)
    if missing:
        raise BackendError(f"backend {backend!r} needs {' and '.join(missing)}: pip install 'tailor[{backend}]'")
    previous = _session
    with contextlib.ExitStack() as stack:
        if backend == "dask":
            _start_dask(stack, jobs, scheduler)
        elif backend == "ray":
            _start_ray(stack, jobs, scheduler)
        session = Session(backend, jobs if backend == "loky" else -1)
        if backend != "loky":
            from joblib import parallel_config

            stack.enter_context(parallel_config(backend=backend))
        _session = session
        try:
            yield session
        finally:
            _session = previous


def _quiet(stack: contextlib.ExitStack, loggers: tuple[str, ...]) -> None:
    """Silence a cluster's client-side loggers until the session ends (after the cluster is stopped): a Ctrl-C
    makes them log the connections it closed as tracebacks, where the command prints one line."""
    for name in loggers:
        logger = logging.getLogger(name)
        stack.callback(logger.setLevel, logger.level)
        logger.setLevel(logging.CRITICAL)


def _start_dask(stack: contextlib.ExitStack, jobs: int, scheduler: str | None) -> None:
    from distributed import Client, LocalCluster

    _quiet(stack, ("distributed", "distributed.client", "tornado", "tornado.application", "asyncio"))

    if scheduler:
        try:
            client = Client(scheduler, timeout=CONNECT_SECONDS)
        except (OSError, TimeoutError, ValueError) as exc:
            raise BackendError(f"cannot join the Dask scheduler at {scheduler}: {exc}") from None
    else:
        cluster = stack.enter_context(LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True,
                                                   dashboard_address=None, silence_logs=logging.ERROR))
        client = Client(cluster)
    stack.callback(client.close)


def _start_ray(stack: contextlib.ExitStack, jobs: int, scheduler: str | None) -> None:
    import ray
    from ray.util.joblib import register_ray

    register_ray()
    try:
        if scheduler:
            ray.init(address=scheduler, log_to_driver=False, logging_level=logging.ERROR)
        else:
            ray.init(num_cpus=jobs, include_dashboard=False, log_to_driver=False, logging_level=logging.ERROR)
    except (ConnectionError, RuntimeError, ValueError) as exc:
        raise BackendError(f"cannot start or join a Ray cluster{' at ' + scheduler if scheduler else ''}: {exc}") \
            from None
    stack.callback(ray.shutdown)


def active_backend() -> str:
    """The name of the backend in force ("loky" outside any session)."""
    return "loky" if _session is None else _session.backend


@contextlib.contextmanager
def remembered_interrupts():
    """Ctrl-C raises KeyboardInterrupt as always, and is also remembered (the context's value says whether one
    came): one that lands in a callback whose exceptions Python drops (pymunk frees its shapes in a cffi
    garbage-collection callback) is raised again by whoever checks. Only where Python's own handler is in
    force, in the main thread; elsewhere nothing is changed and nothing remembered."""
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGINT) is not signal.default_int_handler):
        yield lambda: False
        return
    seen: list[int] = []

    def handler(signum, frame):
        seen.append(signum)
        raise KeyboardInterrupt

    signal.signal(signal.SIGINT, handler)
    try:
        yield lambda: bool(seen)
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)


def ordered_results(function: Callable, calls: Sequence[tuple], jobs: int = 1, one_by_one: bool = False) -> Iterator:
    """Yield `function(*args)` for each `args` in `calls`, in that order. On loky with jobs = 1, in this process;
    otherwise in the workers of the session's backend (loky: `jobs` processes; a cluster: all its workers).
    `one_by_one` hands the workers one call at a time (for a few calls of tens of milliseconds, which joblib's
    automatic batching would otherwise bundle onto one worker). Closing the iterator (as a `finally` does on
    Ctrl-C) stops the workers' pending calls."""
    calls = list(calls)
    if _session is None or _session.backend == "loky":
        if jobs <= 1:
            with remembered_interrupts() as interrupted:
                for args in calls:
                    result = function(*args)
                    if interrupted():  # a Ctrl-C that a callback swallowed during the call
                        raise KeyboardInterrupt
                    yield result
            return
        n_jobs = jobs
    else:
        n_jobs = _session.n_jobs
    from joblib import Parallel, delayed, effective_n_jobs
    from joblib.parallel import get_active_backend

    backend, _ = get_active_backend()
    batch_size = 1 if one_by_one else "auto"
    if getattr(backend, "supports_return_generator", False):
        results = Parallel(n_jobs=n_jobs, return_as="generator", batch_size=batch_size)(
            delayed(function)(*args) for args in calls)
        try:
            yield from results
        finally:
            results.close()  # on Ctrl-C this stops the workers before KeyboardInterrupt propagates
        return
    with Parallel(n_jobs=n_jobs, batch_size=batch_size) as parallel:  # one pool for every wave
        wave = WAVE_PER_WORKER * max(1, effective_n_jobs(n_jobs))
        for start in range(0, len(calls), wave):
            yield from parallel(delayed(function)(*args) for args in calls[start:start + wave])


def run_in_workers(function, items, jobs: int, desc: str, progress: bool = True, unit: str = "ep") -> list:
    """function(*item) for every item, in order, in `jobs` workers of the backend session in force (loky by
    default, tailor.sims.parallel); one bar for the whole run on a terminal, log lines elsewhere (stage_bar).
    Ctrl-C stops the workers."""
    items = list(items)
    results = []
    with stage_bar(len(items), desc, unit, progress) as bar:
        ordered = ordered_results(function, items, jobs)
        try:
            for result in ordered:
                results.append(result)
                bar.update()
        finally:
            ordered.close()
    return results
