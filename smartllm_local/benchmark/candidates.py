"""The ceiling of choosing among candidates, measured: whether any candidate meets the task's goals (pass@N) and
whether the chosen one does, each candidate dry-run as the verifier runs it.

The task's goals are read here, after planning, to measure only; the planner never sees them.
"""

from __future__ import annotations

from typing import Any

from ..errors import PlanError
from ..plan_language import parse_plan
from ..planner.result import PlanResult
from ..planner.verifier import check_decomposition
from ..scene import SceneObjects
from ..skills import SkillSet
from .tasks import Task

#: What a results line keeps of each candidate (its text stays in the task's candidates.json).
_KEPT = ("candidate", "temperature", "seed", "mean_logprob", "check", "score", "chosen")


def candidate_measures(result: PlanResult, task: Task, skills: SkillSet, scene: SceneObjects) -> dict[str, Any]:
    """A results line's ``candidates`` (each one's check, score and whether its dry run meets the task's goals)
    and ``pass_at_n`` (whether any does; None for an infeasible task); nothing where one candidate was written."""
    record = result.stages.get("decomposition")
    if record is None or not record.candidates:
        return {}
    conditions = [c for g in task.goals for c in g.conditions()]
    rows = []
    for candidate in record.candidates:
        row = {k: candidate.get(k) for k in _KEPT}
        row["meets_task_goals"] = _meets(candidate, skills, scene, conditions) if task.feasible else None
        rows.append(row)
    passed = [r["meets_task_goals"] for r in rows]
    return {"candidates": rows, "pass_at_n": any(passed) if task.feasible else None}


def _meets(candidate: dict[str, Any], skills: SkillSet, scene: SceneObjects, conditions: list) -> bool:
    if candidate.get("check") is None:  # a refusal or a broken plan
        return False
    try:
        plan = parse_plan(candidate["output"], form="decomposed", skills=skills, scene_types=scene.types)
    except PlanError:
        return False
    check = check_decomposition(plan, scene, skills, conditions, idle=False)
    return bool(conditions) and check.met == check.goals
