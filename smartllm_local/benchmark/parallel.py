"""Tasks planned several at once (``benchmark run --parallel K``), executed and scored while others are planned.

Each worker (a method on a lane of one model, or on a server's slot) runs in a thread of its own and takes, when
free, the next pass of stages of any task: the lowest pass first, then the first task in the run's order. So
the workers go through the tasks stage by stage, as one worker does (a stage's examples stay in the lanes'
cache or a slot's, shared by the tasks at that stage), but never wait for the slowest task of a stage before
starting the next. The calling thread executes and scores the tasks in the run's order, each as soon as its
planning is over: the results file is in task order whatever K is.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from typing import Generic, TypeVar

Worker = TypeVar("Worker")
Item = TypeVar("Item")


class _Board(Generic[Item]):
    """What is left to plan, shared by the workers and the executing thread (every field under ``cond``)."""

    def __init__(self, todo: Sequence[Sequence[int]]):
        self.cond = threading.Condition()
        self.todo = [list(passes) for passes in todo]  # each task's passes still to run, in order
        self.busy = [False] * len(todo)
        self.over = [not passes for passes in todo]  # planned, failed or refused: ready to execute
        self.stop = False
        self.failure: BaseException | None = None

    def take(self) -> tuple[int, int] | None:
        """The next (task, pass) to plan, marked busy; None when there is none and none can come (or stop)."""
        while not self.stop:
            ready = [(passes[0], k) for k, passes in enumerate(self.todo)
                     if passes and not self.busy[k] and not self.over[k]]
            if ready:
                number, k = min(ready)
                self.busy[k] = True
                return k, number
            if all(self.over):
                return None
            self.cond.wait()
        return None


def plan_and_execute(items: Sequence[Item], todo: Sequence[Sequence[int]], workers: Sequence[Worker],
                     plan: Callable[[Worker, Item, int], None], goes_on: Callable[[Item], bool],
                     execute: Callable[[int, Item], None], interrupt: Callable[[], None]) -> None:
    """Plan ``items`` on the ``workers`` at once (``plan(worker, item, pass)`` for each pass in ``todo[k]``, while
    ``goes_on(item)``) and ``execute(k, item)`` each, in order, here. ``plan`` must catch what its task may raise.

    On any exception here (Ctrl-C, a failed execution) or a worker's: no pass starts again, ``interrupt()`` ends
    the passes in flight, and every worker's thread has ended before this raises."""
    board: _Board[Item] = _Board(todo)

    def work(worker: Worker) -> None:
        try:
            while True:
                with board.cond:
                    taken = board.take()
                if taken is None:
                    return
                k, number = taken
                plan(worker, items[k], number)
                with board.cond:
                    board.busy[k] = False
                    board.todo[k].pop(0)
                    board.over[k] = not board.todo[k] or not goes_on(items[k])
                    board.cond.notify_all()
        except BaseException as exc:  # noqa: BLE001 - a bug here must stop the run, not hang it
            with board.cond:
                board.failure, board.stop = board.failure or exc, True
                board.cond.notify_all()

    threads = [threading.Thread(target=work, args=(w,), name=f"planner-{n}", daemon=True)
               for n, w in enumerate(workers)]
    for thread in threads:
        thread.start()
    try:
        for k, item in enumerate(items):
            with board.cond:
                while not board.over[k] and board.failure is None:
                    board.cond.wait(0.5)  # a timeout, so that Ctrl-C is heard while waiting
                if board.failure is not None:
                    raise board.failure
            execute(k, item)
    except BaseException:
        with board.cond:
            board.stop = True
            board.cond.notify_all()
        interrupt()
        raise
    finally:
        for thread in threads:
            thread.join()
