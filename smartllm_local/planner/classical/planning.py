"""From goal conditions to an allocated plan: the problem, Fast Downward's search, the threads.

The result is a stage record like a model's: ``output`` holds the allocated plan (or the planner's
refusal), ``prompt`` the PDDL the planner read (domain, then problem), ``raw`` its log and the plan it
found, so a run folder keeps what a planning researcher needs to rerun the search elsewhere.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import Any, Protocol

from ...domain import AI2THOR
from ...errors import UserError
from ...executor.dry_run import DryRun
from ...plan_language import parse_plan
from ...robots import Robot
from ...scoring import Condition
from ...skills import SkillSet
from ...worlds import Ai2ThorWorld, SimulatedSite, World
from ..asked import as_goal
from ..result import StageRecord
from .problem import PlanningTask, Unreachable, planning_task
from .search import GREEDY, SEARCH, UP_LOCK, Search, Step, search
from .site import site_planning_task
from .threads import Part, parts, plan_text, robot_parts, spread

STAGE = "allocation"
REFUSED_BY = "planner"
#: Seconds of Fast Downward's processor time for the shortest plan (the household's take 0.1-9 s) before the
#: greedy search is asked for any plan.
SHORTEST_CPU = 10


class GoalPlanning(Protocol):
    """How one kind of world's rules become a planning task, and its plan threads: what the goal-planner asks
    a world (the world sits below the planner, so its planning model is here, in :data:`GOAL_PLANNING`)."""

    where: str  # what the world of a task is called in a refusal ("scene", "site")

    def task(self, conditions: Sequence[Condition], name: str) -> PlanningTask: ...
    def threads(self, task: PlanningTask, found: Search) -> tuple[list[Step], list[Part], str]: ...


class HouseholdPlanning:
    """AI2-THOR's rules (:mod:`.problem`) on the dry run's copy of the scene: Fast Downward's shortest plan,
    its steps spread over the team's robots."""

    where = "scene"

    def __init__(self, world: Ai2ThorWorld, floor_plan: str | int, team: Sequence[Robot], skills: SkillSet):
        self.dry: DryRun = world.dry_run(floor_plan, skills, team)
        self.team, self.skills = team, skills

    def task(self, conditions: Sequence[Condition], name: str) -> PlanningTask:
        return planning_task(self.dry, self.team, self.skills, conditions, name=name)

    def threads(self, task: PlanningTask, found: Search) -> tuple[list[Step], list[Part], str]:
        split = parts(found.steps, self.dry.objects)
        _, steps, split = spread(task, found.actions, list(found.steps), split, len(self.team))
        return steps, split, "shortest plan"


class SitePlanning:
    """A site domain's rules (:mod:`.site`, from its domain file): a call by more robots costs more, so the
    plan is the cheapest in robot-calls, and steps of different robots commute (a part is the steps that share
    robots)."""

    where = "site"

    def __init__(self, world: SimulatedSite, floor_plan: str | int, team: Sequence[Robot], skills: SkillSet):
        self.world, self.team = world, team

    def task(self, conditions: Sequence[Condition], name: str) -> PlanningTask:
        return site_planning_task(self.world.domain, self.team, conditions, name=name)

    def threads(self, task: PlanningTask, found: Search) -> tuple[list[Step], list[Part], str]:
        return list(found.steps), robot_parts(found.steps), "plan with the fewest robot-calls"


#: Each kind of world's planning model (a world's ``kind``), made for one task's world, scene, team and skills.
GOAL_PLANNING: dict[str, Callable[[Any, str | int, Sequence[Robot], SkillSet], GoalPlanning]] = {
    AI2THOR: HouseholdPlanning,
    "site": SitePlanning,
}


def goal_planning(world: World, floor_plan: str | int, team: Sequence[Robot], skills: SkillSet) -> GoalPlanning:
    """The planning model of ``world``'s kind for one task.

    Raises:
        UserError: no planning model is written for the world's kind (the goal-planner cannot plan there).
    """
    make = GOAL_PLANNING.get(world.kind)
    if make is None:
        raise UserError(f"the goal-planner has no planning model for a world of kind {world.kind!r} (it has "
                        f"{', '.join(GOAL_PLANNING)}): plan with another --method, or add one to "
                        "smartllm_local.planner.classical.planning.GOAL_PLANNING")
    return make(world, floor_plan, team, skills)


def plan_to_goal(conditions: Sequence[Condition], floor_plan: str | int, team: Sequence[Robot], skills: SkillSet,
                 *, time_limit: float, name: str = "task", world: World | None = None,
                 shortest_cpu: int = SHORTEST_CPU) -> StageRecord:
    """Plan for ``team`` in ``floor_plan`` of ``world`` (default AI2-THOR's) until every condition holds (the
    scorer's conditions): the shortest plan, or where ``shortest_cpu`` seconds of Fast Downward's processor time
    do not find it, the greedy search's plan in the wall-clock time left."""
    started = time.perf_counter()
    record = StageRecord(STAGE)
    world = world or Ai2ThorWorld()
    out_of_reach = world.unattainable([as_goal(c) for c in conditions], team, skills, floor_plan)
    if out_of_reach:  # a skill no robot has: no search need prove it (one could take past the time limit)
        _refuse(record, f"the planner found no plan: {'; '.join(out_of_reach)}")
        record.seconds = time.perf_counter() - started
        return record
    model = goal_planning(world, floor_plan, team, skills)
    with UP_LOCK:
        try:
            task = model.task(conditions, _problem_name(name))
        except Unreachable as exc:
            _refuse(record, f"the planner found no plan: {exc}")
            record.seconds = time.perf_counter() - started
            return record
        found = _search_within(task, time_limit - (time.perf_counter() - started), cpu_limit=shortest_cpu)
        if found.out_of_cpu:
            found = _search_within(task, time_limit - (time.perf_counter() - started), config=GREEDY)
    record.prompt = (f";; domain.pddl\n{found.domain_pddl}\n;; problem.pddl\n{found.problem_pddl}")
    record.raw = found.log + _plan_log(found)
    if found.timed_out:
        record.error = (f"the planner's time limit ran out: Fast Downward found no plan in {time_limit:g} s "
                        "(raise it with --planner-time-limit)")
    elif found.unsolvable:
        _refuse(record, f"the planner found no plan: the team cannot reach the goal in this {model.where} "
                        f"(Fast Downward proved it: {found.status})")
    elif not found.steps:
        record.error = "the goal holds already: there is nothing to plan"
    else:
        steps, split, what = model.threads(task, found)
        if not found.shortest:
            what = f"plan, not proven the shortest (none in {shortest_cpu} s of {SEARCH})"
        record.output = plan_text(steps, split, f"goal-planner: Fast Downward's {what} ({found.config}), "
                                                f"{len(steps)} steps, in {len(split)} part(s) run in parallel\n\n")
        record.plan = parse_plan(record.output, form="allocated", skills=skills, team_size=len(team),
                                 name="<goal-planner allocation>")
    record.seconds = time.perf_counter() - started
    return record


def _search_within(task: PlanningTask, left: float, **how: Any) -> Search:
    """The search in the ``left`` seconds of the time limit that building the problem (and any search before)
    left; none where nothing is left."""
    return search(task, left, **how) if left > 0 else Search(timed_out=True)


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

