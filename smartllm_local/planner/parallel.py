"""Planners for tasks planned at once (``benchmark run --parallel K``): one per lane of one in-process llama.cpp
model (:mod:`.backends.lanes`: the K tasks' tokens evaluated in shared batches), or one per server slot.

A planner set owns its backends: :meth:`PlannerSet.interrupt` ends what is in flight (the lanes are closed, so
a lane waiting for a batch raises at once; a server's connections are closed, so a request waiting on it
raises), and :meth:`PlannerSet.close` then frees the model. A caller that runs planners in threads of its own
interrupts, joins its threads, then closes: nothing then touches a model that is freed under it.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable, Sequence

from ..errors import UserError
from .backends.base import Backend
from .backends.lanes import open_lanes
from .pipeline import Planner


class PlannerSet:
    """``make(backend)`` for each backend, or, with ``lanes`` above 1, for each of that many lanes of the one
    backend given."""

    def __init__(self, backends: Sequence[Backend], lanes: int, make: Callable[[Backend], Planner]):
        self._backends = list(backends)
        self._lanes = contextlib.ExitStack()
        self._lock = threading.Lock()
        self._interrupted = self._closed = False
        try:
            views = self._backends
            if lanes > 1:
                views, together = self._lanes.enter_context(open_lanes(self._backends[0], lanes))
                if not together:
                    raise UserError(f"{type(self._backends[0]).__name__} decodes one sequence at a time: "
                                    "--parallel needs --backend llamacpp or server")
            self.planners = [make(view) for view in views]
        except BaseException:
            self.close()
            raise

    def interrupt(self) -> None:
        """End what the planners have in flight: their calls raise, at once (see the module's docstring)."""
        with self._lock:
            if self._interrupted:
                return
            self._interrupted = True
        self._lanes.close()
        for backend in self._backends:
            if getattr(backend, "name", "") == "server":
                backend.close()

    def close(self) -> None:
        """Interrupt, then free the backends (once)."""
        self.interrupt()
        with self._lock:
            if self._closed:
                return
            self._closed = True
        for backend in self._backends:
            backend.close()

    def __enter__(self) -> PlannerSet:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
