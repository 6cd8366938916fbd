"""A method is a list of steps, and one loop runs them: the only place a task goes from one stage to the next.

Each step is named for the stage whose record it adds to the task's :class:`~.result.PlanResult` (as
inspect_ai composes a solver from steps over one task state). The ``plan`` command runs the planner's
steps (:meth:`~.pipeline.Planner.steps`: SMART-LLM's stages as its configuration has them); a benchmark
method runs its own list of them, a pass of steps over every task at a time (:mod:`...benchmark.run`), but
always through :func:`run_steps`, so which stage runs next, and when a task stops, is decided here alone.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from .result import PlanResult, StageRecord


@dataclass(frozen=True)
class Step:
    """One stage of a method: ``run`` adds the record named ``name`` to the task's result. A step that
    ``follows`` goes on in the context of the step before it: a runner that takes many tasks through a
    stage at a time runs it for a task right after that step, on the same worker, before the next task's."""

    name: str
    run: Callable[[PlanResult], object]
    follows: bool = False


def run_steps(
    steps: Sequence[Step],
    result: PlanResult,
    *,
    starting: Callable[[Step], None] = lambda step: None,
    finished: Callable[[StageRecord], None] = lambda record: None,
    failed: Callable[[Step, Exception], None] | None = None,
) -> None:
    """Take a task through ``steps`` in order: a step whose record the result holds already (a resumed run)
    is passed over, and the task stops at the first stage that refuses it or fails.

    Args:
        starting: hears of each step about to run.
        finished: gets the record each step that ran added.
        failed: gets a step's exception, and the task stops there (None: the exception propagates).
    """
    for step in steps:
        if step.name in result.stages:
            continue
        if not result.goes_on:
            return
        starting(step)
        try:
            step.run(result)
        except Exception as exc:
            if failed is None:
                raise
            failed(step, exc)
            return
        if step.name in result.stages:
            finished(result.stages[step.name])
