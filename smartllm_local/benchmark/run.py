"""Planning tasks and judging the plans: planner -> executor -> scorer, for one task or a benchmark.

A benchmark run takes every task through one stage before the next (so the
model keeps each stage's examples in its cache), executes every plan with one
Controller, and scores it. A task that fails (a model error, a budget that
cannot hold the output) becomes a result line with its error; the run goes on.
Infeasible tasks are judged on refusal: refusing one is a success, and
refusing a feasible task is a failure.
"""

from __future__ import annotations

import contextlib
import itertools
import json
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..domain import Domain, load_domain
from ..errors import SmartLLMError
from ..executor import Execution
from ..files import write_atomic
from ..planner.pipeline import Planner, restore_stage, write_artifacts
from ..planner.result import PlanResult, StageRecord
from ..planner.steps import Step, run_steps
from ..robots import Catalogue
from ..scoring import Goal, Scores, score_execution
from ..worlds import Ai2ThorWorld, World, world_of
from .candidates import candidate_measures
from .methods import Method, SmartLLM
from .parallel import plan_and_execute
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
            data["tokens"] = {r.stage: {"prompt": r.prompt_tokens, "reused": r.reused_tokens, "prompted": r.prompted,
                                        "generated": r.generated_tokens, "seconds": round(r.seconds, 2),
                                        "prompt_seconds": round(r.prompt_seconds, 2),
                                        "choices": r.choices, "refused": r.refused, "logprob": round(r.logprob, 3),
                                        "completed_lines": r.completed_lines,
                                        **({"repairs": len(r.repairs), "unrepaired": r.unrepaired,
                                            "ended_at_goals": r.ended_at_goals, "finished": r.finish is not None,
                                            "folded": bool(r.finish and r.finish.get("into")),
                                            "errands": len(r.errands), "idle_steps": len(r.idle_steps),
                                            "joined": len(r.joined), "put_away": len(r.put_away), "moved": len(r.moved)}
                                           if r.stage == "decomposition" else {}),
                                        **({"executable": len(r.executable)} if r.stage == "allocation" else {})}
                              for r in self.result.stages.values()}
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


@dataclass(frozen=True)
class _Venue:
    """Where a run's plans are executed: the domain's world, and its reference plans (the Speed measure's)."""

    world: World
    plans: Path


def execute_and_score(result: PlanResult, goals: Sequence[Goal], catalogue: Catalogue, *,
                      trans: int | None = None, max_trans: int | None = None, controller: Any = None,
                      build: str | None = None, world: World | None = None) -> Scores:
    """Run a planned task's allocated plan in ``world`` (default AI2-THOR's) and score it (a refusal runs
    nothing)."""
    return execute_scored(result, goals, catalogue, trans=trans, max_trans=max_trans, controller=controller,
                          build=build, world=world)[1]


def execute_scored(result: PlanResult, goals: Sequence[Goal], catalogue: Catalogue, *,
                   trans: int | None = None, max_trans: int | None = None, controller: Any = None,
                   build: str | None = None, world: World | None = None) -> tuple[Execution, Scores]:
    """:func:`execute_and_score`, with the execution itself (its trace, for trace.json)."""
    if result.plan is None:
        raise SmartLLMError(result.error or "there is no valid plan to execute")
    team = catalogue.team(result.robots)
    execution = (world or Ai2ThorWorld()).run(result.plan, result.floor_plan, team, skills=catalogue.skills,
                                              controller=controller, build=build)
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
    interrupt: Callable[[], None] = lambda: None,
) -> list[TaskOutcome]:
    """Plan (with ``method``; a Planner is SMART-LLM's), execute (in the ``domain``'s world, default
    household's: AI2-THOR) and score every task; write per-task artifacts and results.jsonl under ``out``.

    With a ``store`` (the run folder), each finished stage is saved at once and each scored task's
    line appended at once; tasks and stages the store already holds are not run again. Any
    exception inside a task becomes that task's error and the run goes on; Ctrl-C stops it, and
    the same run started again resumes it. Several methods (the same method on several workers: lanes
    of one model, a server's slots) plan that many tasks at once, each task on one worker at a time, while
    the tasks planned are executed (:mod:`.parallel`); ``interrupt`` then ends the workers' calls in flight
    when the run stops. Returns the outcomes of the tasks run this time.
    """
    domain = domain or load_domain()
    venue = _Venue(world_of(domain), domain.plans_dir())
    methods = [SmartLLM(m, catalogue) if isinstance(m, Planner) else m
               for m in (method if isinstance(method, Sequence) else [method])]
    done = store.results() if store is not None else {}
    outcomes = [TaskOutcome(task) for task in tasks if task.id not in done]
    live: list[TaskOutcome] = []
    for outcome in outcomes:
        task = outcome.task
        outcome.result = PlanResult(instruction=task.instruction, floor_plan=task.floor_plan, robots=list(task.robots))
        if store is not None:
            _restore(store, catalogue, outcome, venue.world, methods[0].steps(task))
        if _goes_on(outcome):
            live.append(outcome)
    counts = _Counts(len(methods[0].steps(outcomes[0].task)) if outcomes else 0, len(outcomes), progress)
    if len(methods) == 1:
        _plan_all(outcomes, live, methods[0], store, counts)
        _execute_all(outcomes, catalogue, venue, build, out, store, counts)
    else:
        _plan_and_execute(outcomes, live, methods, catalogue, venue, build, out, store, counts, interrupt)
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


def _plan_all(outcomes: list[TaskOutcome], live: list[TaskOutcome], method: Method, store: RunStore | None,
              counts: _Counts) -> None:
    """Take the live tasks through the method's steps, a pass of steps at a time; a failure costs its task
    (recorded as its error), and each finished stage is saved at once."""
    passes = {id(o): _passes(method.steps(o.task)) for o in live}
    for k, group in enumerate(next(iter(passes.values()), [])):
        # Where each stage's progress count starts: after the tasks done before, or out of the run.
        order = {number: itertools.count(len(outcomes) - sum(not _has(o, step.name) for o in live))
                 for number, step in group}

        def report(number: int, step: Step, outcome: TaskOutcome) -> None:
            counts.step(step.name, outcome.task.id, number * len(outcomes) + next(order[number]))

        for outcome in live:
            if not all(_has(outcome, step.name) for _, step in group):
                _plan_pass(outcome, passes[id(outcome)][k], store, report)
        live = [o for o in live if _goes_on(o)]


def _plan_pass(outcome: TaskOutcome, group: Sequence[tuple[int, Step]], store: RunStore | None,
               report: Callable[[int, Step, TaskOutcome], None], lock: threading.Lock | None = None) -> None:
    """Run one task's pass of steps (those not done yet, :func:`run_steps`); a failure becomes the task's error,
    and each finished stage is saved at once (``lock``: what the run's threads share, the store and the
    progress)."""
    result = outcome.result
    assert result is not None
    shared = lock or contextlib.nullcontext()
    numbers = {step.name: number for number, step in group}

    def starting(step: Step) -> None:
        with shared:
            report(numbers[step.name], step, outcome)

    def finished(record: StageRecord) -> None:
        if store is not None:
            with shared:
                store.save_stage(outcome.task.id, record)

    def failed(step: Step, exc: Exception) -> None:
        # a bug or a backend failure costs this task, not the run
        why = str(exc) if isinstance(exc, SmartLLMError) else f"{type(exc).__name__}: {exc}"
        outcome.error = f"{step.name}: {why}"

    run_steps([step for _, step in group], result, starting=starting, finished=finished, failed=failed)


def _plan_and_execute(outcomes: list[TaskOutcome], live: list[TaskOutcome], methods: Sequence[Method],
                      catalogue: Catalogue, venue: _Venue, build: str | None, out: Path | None,
                      store: RunStore | None, counts: _Counts, interrupt: Callable[[], None]) -> None:
    """Plan the live tasks on every worker at once and execute each, in the run's order, once it is planned
    (:func:`.parallel.plan_and_execute`); progress counts each stage and execution as it starts."""
    going = {id(o) for o in live}
    todo = [[n for n, group in enumerate(_passes(methods[0].steps(o.task)))
             if not all(_has(o, step.name) for _, step in group)] if id(o) in going else [] for o in outcomes]
    left = sum(not _has(o, step.name) for o in live for step in methods[0].steps(o.task)) + len(outcomes)
    done = itertools.count(counts.total - left)
    lock = threading.Lock()
    controller: list[Any] = [None]  # the one Controller of the executions, replaced after a failure

    def plan(method: Method, outcome: TaskOutcome, number: int) -> None:
        _plan_pass(outcome, _passes(method.steps(outcome.task))[number], store,
                   lambda _, step, o: counts.step(step.name, o.task.id, next(done)), lock)

    def execute(_: int, outcome: TaskOutcome) -> None:
        with lock:
            counts.step("execution", outcome.task.id, next(done))
        controller[0] = _execute_one(outcome, catalogue, venue, build, out, store, counts, controller[0], lock)

    try:
        plan_and_execute(outcomes, todo, methods, plan, _goes_on, execute, interrupt)
        if outcomes:
            counts.step("done", "", counts.total)
    finally:
        if controller[0] is not None:
            controller[0].stop()


def _execute_all(outcomes: list[TaskOutcome], catalogue: Catalogue, venue: _Venue, build: str | None,
                 out: Path | None, store: RunStore | None, counts: _Counts) -> None:
    """Execute and score every planned task on one Controller (a fresh one after a failure leaves it in an
    unknown state), writing each task's artifacts and results line as soon as it is scored."""
    controller = None
    try:
        for k, outcome in enumerate(outcomes):
            counts.step("execution", outcome.task.id, counts.stages * len(outcomes) + k)
            controller = _execute_one(outcome, catalogue, venue, build, out, store, counts, controller)
        if outcomes:
            counts.step("done", "", counts.total)
    finally:
        if controller is not None:
            controller.stop()


def _execute_one(outcome: TaskOutcome, catalogue: Catalogue, venue: _Venue, build: str | None,
                 out: Path | None, store: RunStore | None, counts: _Counts, controller: Any,
                 lock: threading.Lock | None = None) -> Any:
    """Conclude a planned task, execute and score its plan, write its artifacts and results line; the
    Controller to go on with."""
    result = outcome.result
    assert result is not None
    Planner.conclude(result)
    if not outcome.error and result.error:
        outcome.error = result.error
    started = time.perf_counter()
    if outcome.task.feasible and result.plan is not None and not outcome.error:
        controller = _execute(outcome, catalogue, venue, build, controller)
    scene = venue.world.scene(outcome.task.floor_plan)
    outcome.extra.update(candidate_measures(result, outcome.task, catalogue.skills, scene))
    outcome.seconds = time.perf_counter() - started + sum(r.seconds for r in result.stages.values())
    if out is not None:
        write_artifacts(result, out / outcome.task.id, {"outcome": outcome.as_json()})
        _write_trace(out / outcome.task.id, outcome)
    with lock or contextlib.nullcontext():
        if store is not None:
            store.append_result(outcome.as_json())
        counts.scored.append(outcome)
    return controller


def _execute(outcome: TaskOutcome, catalogue: Catalogue, venue: _Venue, build: str | None,
             controller: Any) -> Any:
    """Execute and score one task's plan; the Controller to go on with (None after one failed oddly)."""
    try:
        if controller is None:
            controller = venue.world.open(outcome.task.floor_plan, len(outcome.task.robots), build)
        outcome.execution, scores = execute_scored(outcome.result, outcome.task.goals, catalogue,
                                                   trans=outcome.task.trans, max_trans=outcome.task.max_trans,
                                                   controller=controller, world=venue.world)
        outcome.scores = scores.with_speed(reference_ticks(outcome.task, catalogue, controller, venue.plans,
                                                           world=venue.world))
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


def _passes(steps: Sequence[Step]) -> list[list[tuple[int, Step]]]:
    """The steps, numbered, in passes over the tasks: a step that follows another joins its pass."""
    passes: list[list[tuple[int, Step]]] = []
    for number, step in enumerate(steps):
        if step.follows and passes:
            passes[-1].append((number, step))
        else:
            passes.append([(number, step)])
    return passes


def _has(outcome: TaskOutcome, stage: str) -> bool:
    return stage in outcome.result.stages  # type: ignore[union-attr]


def _goes_on(outcome: TaskOutcome) -> bool:
    result = outcome.result
    return not (outcome.error or result is None or result.error or result.refusal is not None)


def _restore(store: RunStore, catalogue: Catalogue, outcome: TaskOutcome, world: World,
             steps: Sequence[Step]) -> None:
    """Put back the stages an interrupted run finished for this task (a damaged one is run again, and
    so is one that the next stage goes on from, when that one is not done: the context they share is not saved)."""
    task, result = outcome.task, outcome.result
    assert result is not None
    scene = None
    for record in store.saved_stages(task.id):
        scene = scene or world.scene(task.floor_plan)
        try:
            restore_stage(result, record, catalogue.skills, scene, len(task.robots))
        except SmartLLMError:
            store.forget_stages(task.id, record.stage)
            break
    for before, step in zip(steps, steps[1:]):
        if step.follows and _has(outcome, before.name) and not _has(outcome, step.name) and _goes_on(outcome):
            store.forget_stages(task.id, before.name)
            del result.stages[before.name]
