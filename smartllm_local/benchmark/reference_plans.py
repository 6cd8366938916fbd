"""Checking the benchmark: run every reference plan and sum up per category.

A feasible task's reference plan (``domains/<domain>/benchmark/reference_plans/<id>.py``) is the
proof that the task can be done as written, by that team, in the world the
planners are scored in: it must reach SR = 1 with every action succeeding
(Exe = 1). An infeasible task has no plan; what can be checked without running
is that its team really lacks the skills it lists as missing.

One Controller serves every run: resetting it to the next scene costs far less
than starting a process per task.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from statistics import mean
from typing import Any

from ..domain import Domain, load_domain
from ..errors import UserError
from ..executor import Execution
from ..plan_language import Plan, read_plan
from ..robots import Catalogue, team_skills
from ..scoring import Scores, score_execution
from ..worlds import Ai2ThorWorld, World, world_of
from .tasks import CATEGORIES, Task

METRICS = ("SR", "GCR", "RU", "Exe")
_SHOWN_FAILURES = 3


@dataclass(frozen=True)
class ReferenceResult:
    """One task's check: its scores when its plan ran, and why it failed if it did."""

    task: Task
    scores: Scores | None
    passed: bool
    problem: str = ""

    @property
    def ran(self) -> bool:
        return self.scores is not None


def default_plans_dir() -> Path:
    """The household domain's reference plans."""
    return load_domain().plans_dir()


def check_reference_plans(
    tasks: Iterable[Task],
    plans_dir: Path | str | None = None,
    *,
    build: str | None = None,
    catalogue: Catalogue | None = None,
    domain: Domain | None = None,
) -> list[ReferenceResult]:
    """Run every feasible task's reference plan (in AI2-THOR, or on a site domain's site); check that every
    infeasible task's team lacks its missing skills (and, on a site, cannot meet some goal condition).

    A missing or invalid plan is a failed result and the check goes on.

    Raises:
        WorldError: the AI2-THOR process failed (no later run could be trusted).
    """
    world = world_of(domain or load_domain())
    catalogue = catalogue or (domain or load_domain()).catalogue
    folder = Path(plans_dir) if plans_dir is not None else (domain.plans_dir() if domain else default_plans_dir())
    results: list[ReferenceResult] = []
    controller = None
    try:
        for task in tasks:
            if not task.feasible:
                results.append(_check_infeasible(task, catalogue, world))
                continue
            plan, problem = load_reference_plan(task, catalogue, folder, world)
            if plan is None:
                results.append(ReferenceResult(task, None, False, problem))
                continue
            team = catalogue.team(task.robots)
            if controller is None:
                controller = world.open(task.floor_plan, len(team), build)
            try:
                execution = world.run(plan, task.floor_plan, team, skills=catalogue.skills, controller=controller)
            except UserError as exc:  # the executor's own checks: the plan does not fit the team
                results.append(ReferenceResult(task, None, False, f"invalid reference plan: {exc}"))
                continue
            scores = score_execution(execution, task.goals, trans=task.trans, max_trans=task.max_trans)
            problem = _judge(task, scores, execution)
            results.append(ReferenceResult(task, scores, not problem, problem))
    finally:
        if controller is not None:
            controller.stop()
    return results


def reference_ticks(task: Task, catalogue: Catalogue, controller: Any, plans_dir: Path | None = None, *,
                    world: World | None = None) -> int | None:
    """How many ticks the task's reference plan (in ``plans_dir``, default household's) takes to meet every goal
    condition (None: it has no plan that does), run in ``world`` (default AI2-THOR's) on ``controller`` (the
    Speed measure's yardstick)."""
    world = world or Ai2ThorWorld()
    plan, _ = load_reference_plan(task, catalogue, plans_dir, world) if task.feasible and task.goals else (None, "")
    if plan is None:
        return None
    team = catalogue.team(task.robots)
    execution = world.run(plan, task.floor_plan, team, skills=catalogue.skills, controller=controller)
    scores = score_execution(execution, task.goals)
    return execution.ticks if scores.TCR == 1.0 else None


def load_reference_plan(task: Task, catalogue: Catalogue, plans_dir: Path | None = None,
                        world: World | None = None) -> tuple[Plan | None, str]:
    """The task's reference plan, validated against its team and its scene in ``world`` (default AI2-THOR's),
    or None and why not."""
    path = (plans_dir or default_plans_dir()) / f"{task.id}.py"
    if not path.is_file():
        return None, f"no reference plan: {path} does not exist"
    try:
        types = (world or Ai2ThorWorld()).scene(task.floor_plan).types
        plan = read_plan(path, form="allocated", skills=catalogue.skills, team_size=len(task.robots),
                         scene_types=types)
    except UserError as exc:
        return None, f"invalid reference plan: {exc}"
    if plan.is_refusal:
        return None, f"the reference plan refuses a feasible task: {plan.refusal}"
    return plan, ""


def _check_infeasible(task: Task, catalogue: Catalogue, world: World) -> ReferenceResult:
    """Not run (there is nothing to run); the team must lack every skill listed as missing. Where the world's
    task rules allow it (a site's), a task may list none when the world shows it infeasible: some goal
    condition no plan for the team can meet (an AI2-THOR task lists its missing skills, as SMART-LLM's
    infeasible tasks do)."""
    team = catalogue.team(task.robots)
    by_goals = world.task_rules().infeasible_by_goals
    blocked = world.unattainable(task.goals, team, catalogue.skills, task.floor_plan) if by_goals else []
    if not task.missing_skills and not blocked:
        return ReferenceResult(task, None, False, "an infeasible task must list its missing_skills"
                               + (" or have a goal condition its team cannot meet" if by_goals else ""))
    present = sorted(set(task.missing_skills) & team_skills(team))
    if present:
        return ReferenceResult(task, None, False, f"missing_skills {present} are skills the team has")
    return ReferenceResult(task, None, True)


def _judge(task: Task, scores: Scores, execution: Execution) -> str:
    """Why a reference run falls short of SR = 1 with every action succeeding ("" if it does not)."""
    if scores.SR is None:
        return "cannot be judged: the task has no goal conditions or no trans/max_trans"
    problems = []
    failed = [e for e in execution.trace if not e.success]
    if failed:
        shown = "; ".join(f"tick {e.tick} {e.skill}({', '.join(map(repr, e.objects))}) by robots {e.robots}: {e.error}"
                          for e in failed[:_SHOWN_FAILURES])
        more = f" (and {len(failed) - _SHOWN_FAILURES} more)" if len(failed) > _SHOWN_FAILURES else ""
        problems.append(f"{len(failed)} of {execution.attempted} actions failed: {shown}{more}")
    unmet = [d for d, ok in scores.conditions if not ok]
    if unmet:
        problems.append(f"unmet goal conditions: {', '.join(unmet)}")
    if scores.RU != 1:
        problems.append(f"{execution.transitions} transitions, the task's ground truth is {task.trans}")
    if execution.truncated:
        problems.append("the run hit the tick limit")
    if scores.SR == 1 and not problems:
        return ""
    return "; ".join(problems) or f"SR {scores.SR}"


def category_table(results: Sequence[ReferenceResult]) -> str:
    """Per category: tasks, reference plans passed, and mean SR/GCR/RU/Exe over the plans that ran."""
    feasible = [r for r in results if r.task.feasible]
    order = [c for c in (*CATEGORIES, "uncategorized") if any(r.task.category == c for r in feasible)]
    header = f"{'category':<12}{'tasks':>6}{'passed':>8}" + "".join(f"{m:>7}" for m in METRICS)
    lines = [header, "-" * len(header)]
    for name, group in [(c, [r for r in feasible if r.task.category == c]) for c in order] + [("all", feasible)]:
        if not group:
            continue
        passed = sum(r.passed for r in group)
        cells = "".join(f"{_mean(group, m):>7}" for m in METRICS)
        lines.append(f"{name:<12}{len(group):>6}{f'{passed}/{len(group)}':>8}{cells}")
    infeasible = [r for r in results if not r.task.feasible]
    if infeasible:
        passed = sum(r.passed for r in infeasible)
        lines.append(f"{'infeasible':<12}{len(infeasible):>6}{f'{passed}/{len(infeasible)}':>8}"
                     "  (not run: team checked to lack the missing skills)")
    return "\n".join(lines)


def _mean(group: Sequence[ReferenceResult], metric: str) -> str:
    values = [getattr(r.scores, metric) for r in group if r.scores is not None]
    known = [v for v in values if v is not None]
    return f"{mean(known):.2f}" if known else "n/a"


__all__ = ["ReferenceResult", "category_table", "check_reference_plans", "default_plans_dir", "reference_ticks"]
