"""Planning tasks and judging the plans: planner -> executor -> scorer, for one task or a benchmark.

A benchmark run takes every task through one stage before the next (so the
model keeps each stage's examples in its cache), executes every plan with one
Controller, and scores it. A task that fails (a model error, a budget that
cannot hold the output) becomes a result line with its error; the run goes on.
Infeasible tasks are judged on refusal: refusing one is a success, and
refusing a feasible task is a failure.
"""

from __future__ import annotations

import itertools
import json
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..domain import Domain
from ..errors import SmartLLMError
from ..executor import Execution, run_plan
from ..files import write_atomic
from ..planner.pipeline import Planner, PlanResult, restore_stage, write_artifacts
from ..planner.prompting.scene_context import scene_objects, site_objects
from ..robots import Catalogue
from ..scoring import Goal, Scores, score_execution
from ..world.controller import open_controller
from .candidates import candidate_measures
from .methods import Method, SmartLLM, Stage
from .reference_plans import reference_ticks
from .results import metric_mean, summary_table
from .run_store import RunStore
from .tasks import Task
from .trace_file import TRACE, write_trace


@dataclass
class TaskOutcome:
    task: Task
    result: PlanResult | None = None
    scores: Scores | None = None
    seconds: float = 0.0  # this task's own time: its stages and its execution, not its wait for the others
    error: str = ""
    extra: dict[str, Any] = field(default_factory=dict)
    execution: Execution | None = None  # what its plan did (for trace.json); None where nothing ran

    @property
    def refused(self) -> bool:
        return self.result is not None and self.result.refusal is not None

    @property
    def success(self) -> bool:
        """Infeasible tasks succeed by refusal; feasible ones by SR = 1."""
        if not self.task.feasible:
            return self.refused
        return self.scores is not None and self.scores.SR == 1.0

    def as_json(self) -> dict[str, Any]:
        data: dict[str, Any] = {"id": self.task.id, "category": self.task.category, "feasible": self.task.feasible,
                                "refused": self.refused, "success": self.success, "seconds": round(self.seconds, 2)}
        if self.refused:
            data["refused_by"] = self.result.refused_by  # type: ignore[union-attr]
        if self.scores is not None:
            data.update(self.scores.metrics(), ticks=self.scores.ticks, Speed=self.scores.Speed)
        if self.result is not None:
            data["tokens"] = {r.stage: {"prompt": r.prompt_tokens, "reused": r.reused_tokens,
                                        "generated": r.generated_tokens, "seconds": round(r.seconds, 2),
                                        "prompt_seconds": round(r.prompt_seconds, 2),
                                        "choices": r.choices, "refused": r.refused, "logprob": round(r.logprob, 3),
                                        "completed_lines": r.completed_lines,
                                        **({"repairs": len(r.repairs), "unrepaired": r.unrepaired,
                                            "ended_at_goals": r.ended_at_goals}
                                           if r.stage == "decomposition" else {})}
                              for r in self.result.stages}
            if self.result.notices:
                data["notices"] = self.result.notices
        if self.error:
            data["error"] = self.error
        data.update(self.extra)
        return data


@dataclass(frozen=True)
class Progress:
    """Where a benchmark run is: ``phase`` (a stage, "execution" or "done") of ``task``, with ``done``
    of ``total`` units (a unit per stage and per execution of each task) behind it."""

    phase: str
    task: str
    done: int
    total: int
    scored: Sequence[TaskOutcome]  # this run's tasks scored so far

    @property
    def feasible_scored(self) -> int:
        return sum(o.task.feasible for o in self.scored)

    @property
    def running_sr(self) -> float | None:
        """Mean SR of the feasible tasks scored so far, as the tables count it (an error or a refusal is 0,
        an SR that cannot be judged is left out); None before any."""
        return metric_mean([o.as_json() for o in self.scored if o.task.feasible], "SR")

    def line(self) -> str:
        """One plain line for a log (stderr that is not a terminal)."""
        sr = self.running_sr
        tail = "" if sr is None else f"; SR so far {sr:.2f} over {self.feasible_scored} feasible task(s)"
        return f"[{self.done}/{self.total}] {self.phase} {self.task}".rstrip() + tail


def execute_and_score(result: PlanResult, goals: Sequence[Goal], catalogue: Catalogue, *,
                      trans: int | None = None, max_trans: int | None = None, controller: Any = None,
                      build: str | None = None, site: Domain | None = None) -> Scores:
    """Run a planned task's allocated plan (in AI2-THOR, or on ``site``) and score it (a refusal runs nothing)."""
    return execute_scored(result, goals, catalogue, trans=trans, max_trans=max_trans, controller=controller,
                          build=build, site=site)[1]


def execute_scored(result: PlanResult, goals: Sequence[Goal], catalogue: Catalogue, *,
                   trans: int | None = None, max_trans: int | None = None, controller: Any = None,
                   build: str | None = None, site: Domain | None = None) -> tuple[Execution, Scores]:
    """:func:`execute_and_score`, with the execution itself (its trace, for trace.json)."""
    if result.plan is None:
        raise SmartLLMError(result.error or "there is no valid plan to execute")
    team = catalogue.team(result.robots)
    execution = run_plan(result.plan, result.floor_plan, team, controller=controller, build=build,
                         skills=catalogue.skills, site=site)
    return execution, score_execution(execution, goals, trans=trans, max_trans=max_trans)


def run_benchmark(
    tasks: Sequence[Task],
    method: Method | Planner | Sequence[Method],
    catalogue: Catalogue,
    *,
    out: Path | None = None,
    store: RunStore | None = None,
    build: str | None = None,
    progress: Callable[[Progress], None] = lambda step: None,
    domain: Domain | None = None,
) -> list[TaskOutcome]:
    """Plan (with ``method``; a Planner is SMART-LLM's), execute (in AI2-THOR, or on a site ``domain``'s
    site) and score every task; write per-task artifacts and results.jsonl under ``out``.

    With a ``store`` (the run folder), each finished stage is saved at once and each scored task's
    line appended at once; tasks and stages the store already holds are not run again. Any
    exception inside a task becomes that task's error and the run goes on; Ctrl-C stops it, and
    the same run started again resumes it. Several methods (the same method on several workers,
    such as a server's slots) plan that many tasks of a stage at once, each task on one worker.
    Returns the outcomes of the tasks run this time.
    """
    site = domain.as_site if domain is not None else None
    methods = [SmartLLM(m, catalogue) if isinstance(m, Planner) else m
               for m in (method if isinstance(method, Sequence) else [method])]
    done = store.results() if store is not None else {}
    outcomes = [TaskOutcome(task) for task in tasks if task.id not in done]
    live: list[TaskOutcome] = []
    for outcome in outcomes:
        task = outcome.task
        outcome.result = PlanResult(instruction=task.instruction, floor_plan=task.floor_plan, robots=list(task.robots))
        if store is not None:
            _restore(store, catalogue, outcome, site, methods[0].stages())
        if _goes_on(outcome):
            live.append(outcome)
    counts = _Counts(len(methods[0].stages()), len(outcomes), progress)
    _plan_all(outcomes, live, methods, store, counts)
    _execute_all(outcomes, catalogue, site, build, out, store, counts)
    if out is not None:
        lines = store.results() if store is not None else {o.task.id: o.as_json() for o in outcomes}
        if store is None:
            write_atomic(out / "results.jsonl", "".join(json.dumps(line) + "\n" for line in lines.values()))
        write_atomic(out / "summary.txt", summary_table([lines[t.id] for t in tasks if t.id in lines]) + "\n")
    return outcomes


@dataclass
class _Counts:
    """A run's progress: a unit per stage and per execution of each task, and the tasks scored so far."""

    stages: int
    tasks: int
    report: Callable[[Progress], None]
    scored: list[TaskOutcome] = field(default_factory=list)

    @property
    def total(self) -> int:
        return (self.stages + 1) * self.tasks

    def step(self, stage: str, task_id: str, done: int) -> None:
        self.report(Progress(stage, task_id, done, self.total, self.scored))


def _plan_all(outcomes: list[TaskOutcome], live: list[TaskOutcome], methods: Sequence[Method],
              store: RunStore | None, counts: _Counts) -> None:
    """Take the live tasks through the method's stages, a pass of stages at a time, spread over the workers;
    a failure costs its task (recorded as its error), and each finished stage is saved at once."""
    lock = threading.Lock()
    for group in _passes(methods[0].stages()):
        # Where each stage's progress count starts: after the tasks done before, or out of the run.
        order = {number: itertools.count(len(outcomes) - sum(not _has(o, stage.name) for o in live))
                 for number, stage in group}

        def run(worker: Method, outcome: TaskOutcome) -> None:
            result = outcome.result
            assert result is not None
            for number, stage in group:
                if _has(outcome, stage.name):
                    continue
                if not _goes_on(outcome):
                    return
                with lock:
                    counts.step(stage.name, outcome.task.id, number * len(outcomes) + next(order[number]))
                try:
                    worker.stages()[number].run(outcome.task, result)
                except SmartLLMError as exc:
                    outcome.error = f"{stage.name}: {exc}"
                except Exception as exc:  # a bug or a backend failure costs this task, not the run
                    outcome.error = f"{stage.name}: {type(exc).__name__}: {exc}"
                if store is not None and not outcome.error and result.stages and result.stages[-1].stage == stage.name:
                    with lock:
                        store.save_stage(outcome.task.id, result.stages[-1])

        _spread([o for o in live if not all(_has(o, stage.name) for _, stage in group)], methods, run)
        live = [o for o in live if _goes_on(o)]


def _execute_all(outcomes: list[TaskOutcome], catalogue: Catalogue, site: Domain | None, build: str | None,
                 out: Path | None, store: RunStore | None, counts: _Counts) -> None:
    """Execute and score every planned task on one Controller (a fresh one after a failure leaves it in an
    unknown state), writing each task's artifacts and results line as soon as it is scored."""
    controller = None
    try:
        for k, outcome in enumerate(outcomes):
            result = outcome.result
            assert result is not None
            counts.step("execution", outcome.task.id, counts.stages * len(outcomes) + k)
            Planner.conclude(result)
            if not outcome.error and result.error:
                outcome.error = result.error
            started = time.perf_counter()
            if outcome.task.feasible and result.plan is not None and not outcome.error:
                controller = _execute(outcome, catalogue, site, build, controller)
            scene = site_objects(site) if site is not None else scene_objects(outcome.task.floor_plan)
            outcome.extra.update(candidate_measures(result, outcome.task, catalogue.skills, scene))
            outcome.seconds = time.perf_counter() - started + sum(r.seconds for r in result.stages)
            if out is not None:
                write_artifacts(result, out / outcome.task.id, {"outcome": outcome.as_json()})
                _write_trace(out / outcome.task.id, outcome)
            if store is not None:
                store.append_result(outcome.as_json())
            counts.scored.append(outcome)
        if outcomes:
            counts.step("done", "", counts.total)
    finally:
        if controller is not None:
            controller.stop()


def _execute(outcome: TaskOutcome, catalogue: Catalogue, site: Domain | None, build: str | None,
             controller: Any) -> Any:
    """Execute and score one task's plan; the Controller to go on with (None after one failed oddly)."""
    try:
        if controller is None and site is None:
            controller = open_controller(outcome.task.floor_plan, len(outcome.task.robots), build=build)
        outcome.execution, scores = execute_scored(outcome.result, outcome.task.goals, catalogue,
                                                   trans=outcome.task.trans, max_trans=outcome.task.max_trans,
                                                   controller=controller, site=site)
        outcome.scores = scores.with_speed(reference_ticks(outcome.task, catalogue, controller, site=site))
    except SmartLLMError as exc:
        outcome.error = f"execution: {exc}"
    except Exception as exc:
        outcome.error = f"execution: {type(exc).__name__}: {exc}"
        if controller is not None:  # in an unknown state: the next task gets a fresh one
            controller.stop()
            controller = None
    return controller


def _write_trace(folder: Path, outcome: TaskOutcome) -> None:
    """The task's trace.json, or none (one an earlier run left is removed) where its plan did not run."""
    if outcome.execution is not None and outcome.scores is not None:
        write_trace(folder, outcome.execution, outcome.scores, outcome.task.floor_plan, outcome.task.robots)
    else:
        (folder / TRACE).unlink(missing_ok=True)


def _spread(batch: Sequence[TaskOutcome], workers: Sequence[Method],
            run: Callable[[Method, TaskOutcome], None]) -> None:
    """Run ``batch`` in order on one worker, or on all of them at once (each takes the next task when free)."""
    if len(workers) == 1 or len(batch) < 2:
        for outcome in batch:
            run(workers[0], outcome)
        return
    queue = iter(batch)
    lock = threading.Lock()

    def work(worker: Method) -> None:
        while True:
            with lock:
                outcome = next(queue, None)
            if outcome is None:
                return
            run(worker, outcome)

    pool = ThreadPoolExecutor(max_workers=len(workers), thread_name_prefix="planner")
    futures = [pool.submit(work, w) for w in workers]
    try:
        for future in futures:
            future.result()
    except BaseException:  # Ctrl-C: no new task starts; closing the backends ends those in flight
        queue = iter(())
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown()


def _passes(stages: Sequence[Stage]) -> list[list[tuple[int, Stage]]]:
    """The stages, numbered, in passes over the tasks: a stage that follows another joins its pass."""
    passes: list[list[tuple[int, Stage]]] = []
    for number, stage in enumerate(stages):
        if stage.follows and passes:
            passes[-1].append((number, stage))
        else:
            passes.append([(number, stage)])
    return passes


def _has(outcome: TaskOutcome, stage: str) -> bool:
    return any(r.stage == stage for r in outcome.result.stages)  # type: ignore[union-attr]


def _goes_on(outcome: TaskOutcome) -> bool:
    result = outcome.result
    return not (outcome.error or result is None or result.error or result.refusal is not None)


def _restore(store: RunStore, catalogue: Catalogue, outcome: TaskOutcome, site: Domain | None,
             stages: Sequence[Stage]) -> None:
    """Put back the stages an interrupted run finished for this task (a damaged one is run again, and
    so is one that the next stage goes on from, when that one is not done: the context they share is not saved)."""
    task, result = outcome.task, outcome.result
    assert result is not None
    scene = None
    for record in store.saved_stages(task.id):
        scene = scene or (site_objects(site) if site is not None else scene_objects(task.floor_plan))
        try:
            restore_stage(result, record, catalogue.skills, scene, len(task.robots))
        except SmartLLMError:
            store.forget_stages(task.id, record.stage)
            break
    for before, stage in zip(stages, stages[1:]):
        if stage.follows and _has(outcome, before.name) and not _has(outcome, stage.name) and _goes_on(outcome):
            store.forget_stages(task.id, before.name)
            result.stages = [r for r in result.stages if r.stage != before.name]
