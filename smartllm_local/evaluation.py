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
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Sequence

from .errors import SmartLLMError
from .executor import run_plan
from .files import write_atomic
from .planner.pipeline import Planner, PlanResult, write_artifacts
from .planner.scene_context import scene_objects
from .robots import Catalogue
from .scoring import Goal, Scores, score_execution
from .tasks import CATEGORIES, Task
from .world.controller import open_controller

METRICS = ("SR", "TCR", "GCR", "RU", "Exe")


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
        if self.scores is not None:
            data.update(self.scores.metrics())
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
    planner: Planner,
    catalogue: Catalogue,
    *,
    out: Path | None = None,
    build: str | None = None,
    progress: Callable[[str], None] = lambda message: None,
) -> list[TaskOutcome]:
    """Plan, execute and score every task; write per-task artifacts and results.jsonl under ``out``."""
    outcomes = [TaskOutcome(task) for task in tasks]
    live: list[TaskOutcome] = []
    for outcome in outcomes:
        task = outcome.task
        outcome.result = PlanResult(instruction=task.instruction, floor_plan=task.floor_plan, robots=list(task.robots))
        live.append(outcome)

    def stage(name: str, step: Callable[[TaskOutcome], None]) -> None:
        batch = list(live)
        for k, outcome in enumerate(batch, start=1):
            progress(f"{name} {k}/{len(batch)}: {outcome.task.id}")
            try:
                step(outcome)
            except SmartLLMError as exc:
                outcome.error = f"{name}: {exc}"
            result = outcome.result
            if outcome.error or result is None or result.error or result.refusal is not None:
                live.remove(outcome)

    def decompose(o: TaskOutcome) -> None:
        planner.decompose(o.result, scene_objects(o.task.floor_plan))  # type: ignore[arg-type]

    def coalition(o: TaskOutcome) -> None:
        team = catalogue.team(o.task.robots)
        planner.form_coalition(o.result, o.result.stages[0].plan, team, scene_objects(o.task.floor_plan))  # type: ignore

    def allocate(o: TaskOutcome) -> None:
        team = catalogue.team(o.task.robots)
        stages = o.result.stages  # type: ignore[union-attr]
        coalition_text = stages[1].output if len(stages) > 1 else None
        planner.allocate(o.result, stages[0].plan, coalition_text, team, scene_objects(o.task.floor_plan))  # type: ignore

    stage("decomposition", decompose)
    if planner.config.prompts.coalition:
        stage("coalition", coalition)
    stage("allocation", allocate)

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
                    outcome.scores = execute_and_score(
                        result, outcome.task.goals, catalogue, trans=outcome.task.trans,
                        max_trans=outcome.task.max_trans, controller=controller)
                except SmartLLMError as exc:
                    outcome.error = f"execution: {exc}"
            outcome.seconds = time.perf_counter() - started + sum(r.seconds for r in result.stages)
            if out is not None:
                write_artifacts(result, out / outcome.task.id, {"outcome": outcome.as_json()})
    finally:
        if controller is not None:
            controller.stop()
    if out is not None:
        write_atomic(out / "results.jsonl", "".join(json.dumps(o.as_json()) + "\n" for o in outcomes))
        write_atomic(out / "summary.txt", summary_table(outcomes) + "\n")
    return outcomes


def summary_table(outcomes: Sequence[TaskOutcome]) -> str:
    """Mean metrics per category (feasible tasks) and the refusal rate on infeasible ones.

    A task that produced no run (an error, a refusal) scores 0; a metric a run cannot be judged
    on (no goal conditions, no ground-truth transitions: some imported tasks) is left out of
    that metric's mean rather than counted as 0, and a mean with nothing to average is n/a."""
    lines = [f"{'category':<14}{'tasks':>6}{'errors':>7}" + "".join(f"{m:>7}" for m in METRICS) + f"{'refused':>9}"]
    groups = [(c, [o for o in outcomes if o.task.feasible and o.task.category == c]) for c in (*CATEGORIES, "uncategorized")]
    groups.append(("all feasible", [o for o in outcomes if o.task.feasible]))
    for name, group in groups:
        if not group:
            continue
        errors = sum(1 for o in group if o.error)
        means = []
        for metric in METRICS:
            values = [getattr(o.scores, metric) if o.scores else 0.0 for o in group]
            known = [v for v in values if v is not None]
            means.append(f"{sum(known) / len(known):>7.2f}" if known else f"{'n/a':>7}")
        refused = sum(1 for o in group if o.refused)
        lines.append(f"{name:<14}{len(group):>6}{errors:>7}" + "".join(means) + f"{refused:>9}")
    infeasible = [o for o in outcomes if not o.task.feasible]
    if infeasible:
        refused = sum(1 for o in infeasible if o.refused)
        lines.append(f"{'infeasible':<14}{len(infeasible):>6}{sum(1 for o in infeasible if o.error):>7}"
                     f"   correctly refused {refused}/{len(infeasible)}")
    return "\n".join(lines)
