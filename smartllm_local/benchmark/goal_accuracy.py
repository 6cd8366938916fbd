"""How well the goal stage states a task's goals: precision and recall against the benchmark's goal conditions.

The stage is given the task's instruction and scene only; the task's goals are read here, after it has
answered, to measure. A stated condition is correct when it is one of the task's conditions: the same
object type in the same state, or the same containment (an item counts as its whole where the task's is
a slice of it or the other way round, as the scorer counts a slice of X as X). Each task condition is
recalled at most once. A refusal states nothing.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

from ..goal_language import GoalStatement, condition_line
from ..scoring import Condition
from ..world.object_types import base_type
from .tasks import CATEGORIES, Task

#: The rows of the report: each category's feasible tasks, the infeasible tasks, and the wholes.
ROWS = (*CATEGORIES, "infeasible", "feasible", "all")


def _key(condition: Condition) -> tuple[str, str, str]:
    item = base_type(condition.item).lower() if condition.item else ""
    return condition.subject.lower(), condition.state or "", item


def matches(stated: Sequence[Condition], truth: Sequence[Condition]) -> tuple[int, int]:
    """How many stated conditions are correct, and how many of the task's conditions they recall."""
    wanted = {_key(c) for c in truth}
    said = {_key(c) for c in stated}
    return sum(_key(c) in wanted for c in stated), len(wanted & said)


def unmatched(stated: Sequence[Condition], truth: Sequence[Condition]) -> tuple[list[Condition], list[Condition]]:
    """The stated conditions that are none of the task's, and the task's conditions none stated recalls."""
    wanted = {_key(c) for c in truth}
    said = {_key(c) for c in stated}
    missing = list({_key(c): c for c in truth if _key(c) not in said}.values())
    return [c for c in stated if _key(c) not in wanted], missing


@dataclass
class Tally:
    """One row's counts."""

    tasks: int = 0
    stated: int = 0
    correct: int = 0
    truth: int = 0
    recalled: int = 0
    exact: int = 0  # tasks whose stated conditions are exactly the task's
    refused: int = 0
    errors: int = 0

    def add(self, statement: GoalStatement | None, truth: Sequence[Condition], *, refused: bool) -> None:
        stated = statement.conditions if statement is not None and statement.refusal is None else []
        correct, recalled = matches(stated, truth)
        self.tasks += 1
        self.stated += len(stated)
        self.correct += correct
        self.truth += len({_key(c) for c in truth})
        self.recalled += recalled
        self.exact += bool(stated) and {_key(c) for c in stated} == {_key(c) for c in truth}
        self.refused += refused
        self.errors += statement is None and not refused

    @property
    def precision(self) -> float | None:
        return self.correct / self.stated if self.stated else None

    @property
    def recall(self) -> float | None:
        return self.recalled / self.truth if self.truth else None


@dataclass
class GoalReport:
    rows: dict[str, Tally] = field(default_factory=lambda: {name: Tally() for name in ROWS})
    lines: list[dict[str, Any]] = field(default_factory=list)  # one per task, for the results file

    def table(self) -> str:
        fmt = lambda v: "  n/a" if v is None else f"{v:5.2f}"  # noqa: E731
        out = [f"{'':<11} tasks  precision  recall  exact  refused  stated  correct  conditions  recalled"]
        for name, t in self.rows.items():
            if t.tasks:
                out.append(f"{name:<11} {t.tasks:>5}  {fmt(t.precision):>9}  {fmt(t.recall):>6}  {t.exact:>5}  "
                           f"{t.refused:>7}  {t.stated:>6}  {t.correct:>7}  {t.truth:>10}  {t.recalled:>8}")
        return "\n".join(out)


#: What states a task's goals: given the instruction and the scene, never the task.
StateGoals = Callable[[str, str], tuple[GoalStatement | None, str | None, dict[str, Any]]]


def measure(tasks: Iterable[Task], state: StateGoals) -> GoalReport:
    """Run ``state`` over the tasks (instruction and floor plan only) and score what it stated."""
    report = GoalReport()
    for task in tasks:
        statement, refusal, extra = state(task.instruction, task.floor_plan)
        truth = [c for g in task.goals for c in g.conditions()]
        rows = [task.category if task.feasible else "infeasible", "feasible" if task.feasible else "", "all"]
        for row in filter(None, rows):
            if row in report.rows:
                report.rows[row].add(statement, truth, refused=refusal is not None)
        stated = statement.conditions if statement is not None and statement.refusal is None else []
        correct, recalled = matches(stated, truth)
        report.lines.append({"id": task.id, "category": task.category, "feasible": task.feasible,
                             "stated": [condition_line(c) for c in stated], "refusal": refusal,
                             "truth": [condition_line(c) for c in truth], "correct": correct, "recalled": recalled,
                             **extra})
    return report
