"""Planning tasks and judging the plans: planner -> executor -> scorer, for one task or a benchmark.

A benchmark run takes every task through one stage before the next (so the
model keeps each stage's examples in its cache), executes every plan with one
Controller, and scores it. A task that fails (a model error, a budget that
cannot hold the output) becomes a result line with its error; the run goes on.
Infeasible tasks are judged on refusal: refusing one is a success, and
refusing a feasible task is a failure.
"""

from __future__ import annotations

import json
import statistics
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

from .benchmark import reference_ticks
from .errors import SmartLLMError
from .executor import run_plan
from .files import write_atomic
from .methods import Method, SmartLLM
from .planner.pipeline import Planner, PlanResult, restore_stage, write_artifacts
from .planner.scene_context import scene_objects
from .robots import Catalogue
from .run_store import RunStore
from .scoring import Goal, Scores, score_execution
from .tasks import CATEGORIES, Task
from .world.controller import open_controller

METRICS = ("SR", "TCR", "GCR", "RU", "Exe", "Speed")


@dataclass
class TaskOutcome:
    task: Task
    result: PlanResult | None = None
    scores: Scores | None = None
    seconds: float = 0.0  # this task's own time: its stages and its execution, not its wait for the others
    error: str = ""
    extra: dict[str, Any] = field(default_factory=dict)

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
            data["tokens"] = {r.stage: {"prompt": r.prompt_tokens, "generated": r.generated_tokens,
                                        "seconds": round(r.seconds, 2)} for r in self.result.stages}
            if self.result.notices:
                data["notices"] = self.result.notices
        if self.error:
            data["error"] = self.error
        data.update(self.extra)
        return data


def execute_and_score(result: PlanResult, goals: Sequence[Goal], catalogue: Catalogue, *,
                      trans: int | None = None, max_trans: int | None = None, controller: Any = None,
                      build: str | None = None) -> Scores:
    """Run a planned task's allocated plan and score it (a refusal runs nothing)."""
    if result.plan is None:
        raise SmartLLMError(result.error or "there is no valid plan to execute")
    team = catalogue.team(result.robots)
    execution = run_plan(result.plan, result.floor_plan, team, controller=controller, build=build,
                         skills=catalogue.skills)
    return score_execution(execution, goals, trans=trans, max_trans=max_trans)


def run_benchmark(
    tasks: Sequence[Task],
    method: Method | Planner,
    catalogue: Catalogue,
    *,
    out: Path | None = None,
    store: RunStore | None = None,
    build: str | None = None,
    progress: Callable[[str], None] = lambda message: None,
) -> list[TaskOutcome]:
    """Plan (with ``method``; a Planner is SMART-LLM's), execute and score every task; write per-task
    artifacts and results.jsonl under ``out``.

    With a ``store`` (the run folder), each finished stage is saved at once and each scored task's
    line appended at once; tasks and stages the store already holds are not run again. Any
    exception inside a task becomes that task's error and the run goes on; Ctrl-C stops it, and
    the same run started again resumes it. Returns the outcomes of the tasks run this time.
    """
    if isinstance(method, Planner):
        method = SmartLLM(method, catalogue)
    done = store.results() if store is not None else {}
    outcomes = [TaskOutcome(task) for task in tasks if task.id not in done]
    live: list[TaskOutcome] = []
    for outcome in outcomes:
        task = outcome.task
        outcome.result = PlanResult(instruction=task.instruction, floor_plan=task.floor_plan, robots=list(task.robots))
        if store is not None:
            _restore(store, catalogue, outcome)
        if _goes_on(outcome):
            live.append(outcome)

    for stage in method.stages():
        batch = [o for o in live if not any(r.stage == stage.name for r in o.result.stages)]  # type: ignore[union-attr]
        for k, outcome in enumerate(batch, start=1):
            progress(f"{stage.name} {k}/{len(batch)}: {outcome.task.id}")
            result = outcome.result
            assert result is not None
            try:
                stage.run(outcome.task, result)
            except SmartLLMError as exc:
                outcome.error = f"{stage.name}: {exc}"
            except Exception as exc:  # a bug or a backend failure costs this task, not the run
                outcome.error = f"{stage.name}: {type(exc).__name__}: {exc}"
            if store is not None and not outcome.error and result.stages and result.stages[-1].stage == stage.name:
                store.save_stage(outcome.task.id, result.stages[-1])
            if not _goes_on(outcome):
                live.remove(outcome)

    controller = None
    try:
        for outcome in outcomes:
            result = outcome.result
            assert result is not None
            Planner.conclude(result)
            if not outcome.error and result.error:
                outcome.error = result.error
            started = time.perf_counter()
            if outcome.task.feasible and result.plan is not None and not outcome.error:
                progress(f"execution: {outcome.task.id}")
                try:
                    if controller is None:
                        controller = open_controller(outcome.task.floor_plan, len(outcome.task.robots), build=build)
                    scores = execute_and_score(
                        result, outcome.task.goals, catalogue, trans=outcome.task.trans,
                        max_trans=outcome.task.max_trans, controller=controller)
                    outcome.scores = scores.with_speed(reference_ticks(outcome.task, catalogue, controller))
                except SmartLLMError as exc:
                    outcome.error = f"execution: {exc}"
                except Exception as exc:
                    outcome.error = f"execution: {type(exc).__name__}: {exc}"
                    if controller is not None:  # in an unknown state: the next task gets a fresh one
                        controller.stop()
                        controller = None
            outcome.seconds = time.perf_counter() - started + sum(r.seconds for r in result.stages)
            if out is not None:
                write_artifacts(result, out / outcome.task.id, {"outcome": outcome.as_json()})
            if store is not None:
                store.append_result(outcome.as_json())
    finally:
        if controller is not None:
            controller.stop()
    if out is not None:
        lines = store.results() if store is not None else {o.task.id: o.as_json() for o in outcomes}
        if store is None:
            write_atomic(out / "results.jsonl", "".join(json.dumps(line) + "\n" for line in lines.values()))
        write_atomic(out / "summary.txt", summary_table([lines[t.id] for t in tasks if t.id in lines]) + "\n")
    return outcomes


def _goes_on(outcome: TaskOutcome) -> bool:
    result = outcome.result
    return not (outcome.error or result is None or result.error or result.refusal is not None)


def _restore(store: RunStore, catalogue: Catalogue, outcome: TaskOutcome) -> None:
    """Put back the stages an interrupted run finished for this task (a damaged one is run again)."""
    task, result = outcome.task, outcome.result
    assert result is not None
    scene = None
    for record in store.saved_stages(task.id):
        scene = scene or scene_objects(task.floor_plan)
        try:
            restore_stage(result, record, catalogue.skills, scene, len(task.robots))
        except SmartLLMError:
            store.forget_stages(task.id, record.stage)
            return


def _groups(lines: Sequence[Mapping[str, Any]]) -> list[tuple[str, list[Mapping[str, Any]]]]:
    feasible = [line for line in lines if line["feasible"]]
    groups = [(c, [line for line in feasible if line["category"] == c]) for c in (*CATEGORIES, "uncategorized")]
    return [(name, group) for name, group in [*groups, ("all feasible", feasible)] if group]


def _mean(group: Sequence[Mapping[str, Any]], metric: str) -> float | None:
    """A metric's mean over a group's lines: a line without it (an error, a refusal) counts 0, one
    whose run cannot be judged on it (None) is left out."""
    known = [v for v in (line.get(metric, 0.0) for line in group) if v is not None]
    return sum(known) / len(known) if known else None


def summary_table(lines: Sequence[Mapping[str, Any]]) -> str:
    """Mean metrics per category (feasible tasks) and the refusal rate on infeasible ones, from
    results lines (``TaskOutcome.as_json``).

    A task that produced no run (an error, a refusal) scores 0; a metric a run cannot be judged
    on (no goal conditions, no ground-truth transitions: some imported tasks) is left out of
    that metric's mean rather than counted as 0, and a mean with nothing to average is n/a."""
    rows = [f"{'category':<14}{'tasks':>6}{'errors':>7}" + "".join(f"{m:>7}" for m in METRICS) + f"{'refused':>9}"]
    for name, group in _groups(lines):
        errors = sum(1 for line in group if line.get("error"))
        means = [_mean(group, metric) for metric in METRICS]
        refused = sum(1 for line in group if line["refused"])
        rows.append(f"{name:<14}{len(group):>6}{errors:>7}" + "".join(
            f"{'n/a' if m is None else f'{m:.2f}':>7}" for m in means) + f"{refused:>9}")
    infeasible = [line for line in lines if not line["feasible"]]
    if infeasible:
        refused = [line for line in infeasible if line["refused"]]
        by = Counter(line.get("refused_by") or "model" for line in refused)
        who = ", ".join(f"{by[k]} by {k}" for k in ("model", "grammar", "rule") if by[k] or k != "rule")
        rows.append(f"{'infeasible':<14}{len(infeasible):>6}{sum(1 for line in infeasible if line.get('error')):>7}"
                    f"   correctly refused {len(refused)}/{len(infeasible)} ({who})")
    return "\n".join(rows)


def variability_table(runs: Sequence[Sequence[Mapping[str, Any]]]) -> str:
    """The paper's Table II: per category and metric, the mean and standard deviation over runs
    (seeds) of each run's category mean; and the refusal rate of infeasible tasks likewise."""
    header = f"{'category':<14}{'tasks':>6}{'runs':>5}" + "".join(f"{m:>12}" for m in METRICS)
    rows = [header]
    per_run = [dict(_groups(lines)) for lines in runs]
    for name, group in _groups(runs[0]):
        cells = []
        for metric in METRICS:
            values = [v for v in (_mean(groups.get(name, []), metric) for groups in per_run) if v is not None]
            cells.append(_spread(values))
        rows.append(f"{name:<14}{len(group):>6}{len(runs):>5}" + "".join(f"{c:>12}" for c in cells))
    infeasible = [[line for line in lines if not line["feasible"]] for lines in runs]
    if infeasible[0]:
        rates = [sum(line["refused"] for line in group) / len(group) for group in infeasible if group]
        rows.append(f"{'infeasible':<14}{len(infeasible[0]):>6}{len(runs):>5}   refused {_spread(rates)}")
    return "\n".join(rows)


def _spread(values: Sequence[float]) -> str:
    if not values:
        return "n/a"
    return f"{statistics.fmean(values):.2f}±{statistics.stdev(values) if len(values) > 1 else 0.0:.2f}"
