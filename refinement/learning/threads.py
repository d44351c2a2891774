"""One thread per fit: the parallelism of training is its workers', never the libraries' own thread pools.

HistGradientBoostingRegressor starts an OpenMP thread per CPU; on a busy machine its threads wait for one
another (a fit of 200 examples took 31 s with 2 threads under load, 0.14 s with one). threadpoolctl's
`threadpool_limits` scans the process's loaded libraries on every call (about 4 ms, a few seconds over the
thousand fits of one training); one controller per process, made at first use (after numpy and scikit-learn,
imported here, have loaded their libraries), limits without scanning again.
"""

from __future__ import annotations

import threading

from sklearn.ensemble import HistGradientBoostingRegressor  # noqa: F401  loads the OpenMP runtime the controller limits
from threadpoolctl import ThreadpoolController

_controller: ThreadpoolController | None = None
_lock = threading.Lock()


def one_thread():
    """A context manager limiting the loaded BLAS and OpenMP pools to one thread while it is open."""
    global _controller
    with _lock:
        if _controller is None:
            _controller = ThreadpoolController()
    return _controller.limit(limits=1)
