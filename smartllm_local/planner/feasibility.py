"""Which robots can do what: the team knowledge the coalition and allocation grammars build on.

A robot can use only its own skills and lift up to its mass capacity; a team
pools skills and capacities. The coalition grammar admits, for each sub-task,
only the teams that have every skill its function uses and can lift the
heaviest thing it picks up, and admits only a refusal when some sub-task has
no such team. The allocation grammar admits only robot lists that give every
step a robot (or team) able to do it. This is the catalogue's knowledge, not
the model's: the model still chooses among the teams that can do the work.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations, permutations
from typing import Iterable, Sequence

from ..plan_language import Plan
from ..plan_language.ir import Call, SkillCall
from ..robots import Robot
from .scene_context import SceneObjects

MASS_TOLERANCE = 1e-6  # scene masses are float32
EXACT_COALITIONS = 6  # teams up to this size are enumerated
EXACT_ALLOCATIONS = 5  # robot lists (ordered) up to this team size are enumerated


@dataclass(frozen=True)
class Need:
    """What a sub-task asks of whoever does it."""

    skills: frozenset[str]
    mass: float  # the heaviest object it picks up (kg)


@dataclass(frozen=True)
class Step:
    """One action of an allocated function: who (a robot_list slot, or None for the whole list) does what."""

    slot: int | None
    skill: str
    mass: float  # of the object picked up, else 0


def function_needs(plan: Plan, scene: SceneObjects, pickup_skills: Iterable[str] = ("PickupObject",)) -> dict[str, Need]:
    """The needs of each function of a (decomposed) plan, helper calls included."""
    pickups = set(pickup_skills)
    functions = plan.by_name
    memo: dict[str, Need] = {}

    def need(name: str) -> Need:
        if name not in memo:
            skills: set[str] = set()
            mass = 0.0
            for step in functions[name].body:
                if isinstance(step, SkillCall):
                    skills.add(step.skill)
                    if step.skill in pickups and step.objects:
                        mass = max(mass, scene.masses.get(step.objects[0], 0.0))
                elif isinstance(step, Call):
                    inner = need(step.function)
                    skills |= inner.skills
                    mass = max(mass, inner.mass)
            memo[name] = Need(frozenset(skills), mass)
        return memo[name]

    return {name: need(name) for name in functions}


def can_do(robots: Sequence[Robot], need: Need) -> bool:
    skills = frozenset().union(*(r.skills for r in robots))
    return need.skills <= skills and sum(r.mass_capacity for r in robots) + MASS_TOLERANCE >= need.mass


def feasible_teams(team: Sequence[Robot], need: Need) -> list[tuple[int, ...]] | None:
    """Sets of team indices (in increasing order) that can do the need; None when the team is too big to list."""
    if len(team) > EXACT_COALITIONS:
        return None
    return [c for n in range(1, len(team) + 1) for c in combinations(range(len(team)), n)
            if can_do([team[i] for i in c], need)]


def feasible_lists(team: Sequence[Robot], steps: Sequence[Step], min_length: int) -> list[tuple[int, ...]] | None:
    """Ordered robot lists (robot_list[i] is the i-th) under which every step has a capable actor.

    None when the team is too big to list; empty when no list works.
    """
    if len(team) > EXACT_ALLOCATIONS:
        return None
    good = []
    for n in range(max(1, min_length), len(team) + 1):
        for order in permutations(range(len(team)), n):
            if all(_step_ok([team[i] for i in order], step) for step in steps):
                good.append(order)
    return good


def _step_ok(listed: Sequence[Robot], step: Step) -> bool:
    actors = listed if step.slot is None else [listed[step.slot]]
    return can_do(actors, Need(frozenset({step.skill}), step.mass))
