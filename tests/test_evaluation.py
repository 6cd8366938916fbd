"""The benchmark summary table: what counts as 0 and what is left out of a mean."""

from __future__ import annotations

from smartllm_local.evaluation import TaskOutcome, summary_table
from smartllm_local.scoring import Scores
from smartllm_local.tasks import Task


def _task(task_id: str, category: str = "uncategorized", feasible: bool = True) -> Task:
    return Task(id=task_id, category=category, floor_plan="FloorPlan1", instruction="x", robots=(1,), goals=(),
                trans=None, max_trans=None, feasible=feasible)


def _row(table: str, name: str) -> list[str]:
    return next(line.split() for line in table.splitlines() if line.startswith(name))


def test_unknown_metrics_are_left_out_of_the_means_and_failures_count_as_0():
    judged = Scores(SR=1.0, TCR=1.0, GCR=1.0, RU=1.0, Exe=1.0, transitions=0)
    no_goals = Scores(SR=None, TCR=None, GCR=None, RU=None, Exe=0.5, transitions=0)
    no_trans = Scores(SR=None, TCR=0.0, GCR=0.5, RU=None, Exe=1.0, transitions=1)
    outcomes = [
        TaskOutcome(_task("FloorPlan1-1"), scores=judged),
        TaskOutcome(_task("FloorPlan1-2"), scores=no_goals),
        TaskOutcome(_task("FloorPlan1-3"), scores=no_trans),
        TaskOutcome(_task("FloorPlan1-4"), error="allocation: the model failed"),
    ]
    row = _row(summary_table(outcomes), "uncategorized")
    # category tasks errors SR TCR GCR RU Exe refused
    assert row == ["uncategorized", "4", "1", "0.50", "0.33", "0.50", "0.50", "0.62", "0"]


def test_a_metric_nothing_judges_is_na():
    outcomes = [TaskOutcome(_task("FloorPlan1-1"), scores=Scores(None, None, None, None, 1.0, 0))]
    assert _row(summary_table(outcomes), "uncategorized")[3:7] == ["n/a"] * 4
