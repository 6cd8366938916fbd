"""From goal conditions to an allocated plan: the problem, Fast Downward's search, the threads.

The result is a stage record like a model's: ``output`` holds the allocated plan (or the planner's
refusal), ``prompt`` the PDDL the planner read (domain, then problem), ``raw`` its log and the plan it
found, so a run folder keeps what a planning researcher needs to rerun the search elsewhere.
"""

from __future__ import annotations

import time
from collections.abc import Sequence

from ...domain import Domain
from ...executor.dry_run import DryRun
from ...executor.site import unattainable
from ...plan_language import parse_plan
from ...robots import Robot
from ...scoring import Condition
from ...skills import SkillSet
from ..result import StageRecord
from .problem import PlanningTask, Unreachable, planning_task
from .search import SEARCH, UP_LOCK, Search, search
from .site import goals_of, site_planning_task
from .threads import parts, plan_text, robot_parts, spread

STAGE = "allocation"
REFUSED_BY = "planner"


def plan_to_goal(conditions: Sequence[Condition], floor_plan: str | int, team: Sequence[Robot], skills: SkillSet,
                 *, time_limit: float, name: str = "task", site: Domain | None = None) -> StageRecord:
    """Plan for ``team`` in ``floor_plan`` (or on ``site``, a site domain) until every condition holds (the
    scorer's conditions)."""
    started = time.perf_counter()
    record = StageRecord(STAGE)
    dry = DryRun(floor_plan, team, skills) if site is None else None
    with UP_LOCK:
        try:
            if site is not None:
                task = site_planning_task(site, team, conditions, name=_problem_name(name))
            else:
                assert dry is not None
                task = planning_task(dry, team, skills, conditions, name=_problem_name(name))
        except Unreachable as exc:
            _refuse(record, f"the planner found no plan: {exc}")
            record.seconds = time.perf_counter() - started
            return record
        found = search(task, time_limit)
    record.prompt = (f";; domain.pddl\n{found.domain_pddl}\n;; problem.pddl\n{found.problem_pddl}")
    record.raw = found.log + _plan_log(found)
    if found.timed_out:
        record.error = (f"the planner's time limit ran out: Fast Downward found no plan in {time_limit:g} s "
                        "(raise it with --planner-time-limit)")
    elif found.unsolvable:
        why = "; ".join(unattainable(site, goals_of(conditions), team)) if site is not None else ""
        _refuse(record, f"the planner found no plan: the team cannot reach the goal in this "
                        f"{'scene' if site is None else 'site'} (Fast Downward proved it: {found.status})"
                        + (f": {why}" if why else ""))
    elif not found.steps:
        record.error = "the goal holds already: there is nothing to plan"
    else:
        record.output = _allocated(task, found, dry, len(team))
        record.plan = parse_plan(record.output, form="allocated", skills=skills, team_size=len(team),
                                 name="<goal-planner allocation>")
    record.seconds = time.perf_counter() - started
    return record


def _allocated(task: PlanningTask, found: Search, dry: DryRun | None, team_size: int) -> str:
    """The plan found as sub-tasks run in parallel. On a site (no dry run) a call by more robots costs more,
    so the plan is the cheapest in robot-calls, and steps of different robots commute: a part is the steps
    that share robots."""
    if dry is None:
        steps, split = list(found.steps), robot_parts(found.steps)
        what = "plan with the fewest robot-calls"
    else:
        split = parts(found.steps, dry.objects)
        _, steps, split = spread(task, found.actions, list(found.steps), split, team_size)
        what = "shortest plan"
    return plan_text(steps, split, f"goal-planner: Fast Downward's {what} ({SEARCH}), {len(steps)} steps, "
                                   f"in {len(split)} part(s) run in parallel\n\n")


def _refuse(record: StageRecord, why: str) -> None:
    record.output = f"# INFEASIBLE: {why}\n"
    record.refusal, record.refused_by = why, REFUSED_BY
    record.plan = parse_plan(record.output, form="allocated")


def _plan_log(found: Search) -> str:
    lines = [f"{s.skill}({', '.join(f'robots[{r}]' for r in s.robots)}, {', '.join(map(repr, s.objects))})"
             for s in found.steps]
    return f"\n;; status: {found.status}\n;; plan ({len(lines)} steps)\n" + "".join(f"{line}\n" for line in lines)


def _problem_name(name: str) -> str:
    cleaned = "".join(c if c.isalnum() else "_" for c in name)
    if not cleaned or not cleaned[0].isalpha():
        cleaned = f"task_{cleaned}"
    return cleaned

