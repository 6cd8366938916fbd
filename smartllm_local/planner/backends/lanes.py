"""Several sequences written at once on one backend: its lanes.

A backend that decodes several sequences in one batch provides ``lanes(n)``; any other is driven one
sequence after another.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

from .base import Backend


@contextlib.contextmanager
def open_lanes(backend: Backend, n: int) -> Iterator[tuple[list[Backend], bool]]:
    """n views of ``backend`` for n sequences written at once; the bool says whether the views may be (and should
    be) driven concurrently, one thread each. A backend with a method ``lanes(n)`` (a context manager yielding the
    views) provides them; any other backend gets ([backend] * n, False) and the caller runs the n sequences one
    after another."""
    lanes = getattr(backend, "lanes", None)
    if n <= 1 or lanes is None:
        yield [backend] * n, False
        return
    with lanes(n) as views:
        yield list(views), True
