"""Which robots can do what: the team knowledge the coalition and allocation grammars build on.

A robot can use only its own skills and lift up to its mass capacity; a team
pools skills and capacities. A call may ask more, as its world says
(:meth:`~smartllm_local.worlds.World.call_demand`): on a site, that its robots get
where it acts (a roof: aerial robots only) and, for a patrol, that the members
with the skill pool the region's area. The coalition grammar admits, for each sub-task,
only the teams that have every skill its function uses and can lift the
heaviest thing it picks up (and of those, the minimal ones: no member it could do
without), and admits only a refusal when some sub-task has no such team. The
allocation grammar admits only robot lists that give every step a robot (or team)
able to do it, again with no robot to spare. The decomposition grammar, before them,
admits only the calls the whole team can make (:class:`WholeTeam`), so every sub-task it
writes has a team; a refusal states what the team lacks (:func:`shortfall`). This is the
catalogue's knowledge, not the model's: the model still chooses among the teams that can
do the work.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from itertools import combinations, permutations

from ...domain import pooled
from ...plan_language import Plan
from ...plan_language.ir import Call, SkillCall
from ...robots import Robot, team_lift, team_skills
from ...scene import MASS_TOLERANCE, Demand, SceneObjects

EXACT_COALITIONS = 6  # teams up to this size are enumerated
EXACT_ALLOCATIONS = 5  # robot lists (ordered) up to this team size are enumerated


@dataclass(frozen=True)
class Need:
    """What a sub-task asks of whoever does it."""

    skills: frozenset[str]
    mass: float  # the heaviest object it picks up (kg)
    demands: frozenset[Demand] = frozenset()  # where its calls go, what they pool (as the world asks)


@dataclass(frozen=True)
class Step:
    """One action of an allocated function: who (a robot_list slot, or None for the whole list) does what."""

    slot: int | None
    skill: str
    mass: float  # of the object picked up, else 0
    demand: Demand | None = None  # where the world asks it: every actor must get there (a team goes together)


def function_needs(plan: Plan, scene: SceneObjects,
                   pickup_skills: Iterable[str] = ("PickupObject",)) -> dict[str, Need]:
    """The needs of each function of a (decomposed) plan, helper calls included."""
    pickups = set(pickup_skills)
    functions = plan.by_name
    memo: dict[str, Need] = {}

    def need(name: str) -> Need:
        if name not in memo:
            skills: set[str] = set()
            demands: set[Demand] = set()
            mass = 0.0
            for step in functions[name].body:
                if isinstance(step, SkillCall):
                    skills.add(step.skill)
                    if step.skill in pickups and step.objects:
                        mass = max(mass, scene.masses.get(step.objects[0], 0.0))
                    demand = scene.world.call_demand(step.skill, step.objects)
                    if demand is not None:
                        demands.add(demand)
                elif isinstance(step, Call):
                    inner = need(step.function)
                    skills |= inner.skills
                    demands |= inner.demands
                    mass = max(mass, inner.mass)
            memo[name] = Need(frozenset(skills), mass, frozenset(demands))
        return memo[name]

    return {name: need(name) for name in functions}


def can_do(robots: Sequence[Robot], need: Need) -> bool:
    skills = frozenset().union(*(r.skills for r in robots))
    return need.skills <= skills and team_lift(robots) + MASS_TOLERANCE >= need.mass \
        and all(d.met_by(robots) for d in need.demands)


def shortfall(team: Sequence[Robot], need: Need, lifted: str = "what it picks up") -> list[str]:
    """Why the whole team cannot do ``need`` (nothing when it can), each reason a fact of the catalogue: the
    skills no robot has, a mass beyond what all lift together (``lifted`` names what is lifted), a place no
    robot with the skill gets to, or a pooled capacity short of what the place asks. A team that cannot do a
    need has no coalition that can (skills, capacities and reach only grow with more robots)."""
    have = team_skills(team)
    reasons = []
    missing = sorted(need.skills - have)
    if missing:
        reasons.append(f"no robot of the team has {', '.join(missing)}")
    lift = team_lift(team)
    if need.mass > lift + MASS_TOLERANCE:
        reasons.append(f"{lifted} weighs {need.mass:g} kg, more than the team lifts together ({lift:g} kg)")
    for d in sorted(need.demands, key=lambda d: (d.place.name, d.skill)):
        if d.skill not in have or d.met_by(team):
            continue
        able = [r for r in team if d.skill in r.skills and d.place.reachable_by(r)]
        if not any(d.place.reachable_by(r) for r in team):
            reasons.append(f"no robot of the team gets to {d.place.name} "
                           f"({' or '.join(sorted(d.place.reach or ()))} robots only)")
        elif not able:
            reasons.append(f"no robot of the team with {d.skill} gets to {d.place.name}")
        elif d.capacity == "camera_range":
            reasons.append(f"no robot of the team with {d.skill} that gets to {d.place.name} has a camera")
        else:
            reasons.append(f"the robots of the team with {d.skill} that get to {d.place.name} pool "
                           f"{pooled(able, d.skill, d.capacity):g} {d.capacity}, less than its {d.amount:g}")
    return list(dict.fromkeys(reasons))  # a place no robot gets to, once


class WholeTeam:
    """The calls a plan for ``team`` may make: those all its robots together can make. A call the whole team
    cannot make no coalition of it can; one it can, some coalition can (the whole team at most), so a
    decomposition made of such calls leaves the coalition a team for every sub-task (lifting together
    included)."""

    def __init__(self, team: Sequence[Robot], scene: SceneObjects, pickup_skills: Iterable[str]):
        self.team = list(team)
        self.scene = scene
        self.pickups = frozenset(pickup_skills)
        self.skills = team_skills(self.team)
        self._memo: dict[tuple[str, str], bool] = {}

    def need(self, skill: str, objects: Sequence[str]) -> Need:
        """What one call asks: its skill, the mass of what it picks up, and what else its world asks (where it goes)."""
        mass = self.scene.masses.get(objects[0], 0.0) if skill in self.pickups and objects else 0.0
        demand = self.scene.world.call_demand(skill, objects)
        return Need(frozenset({skill}), mass, frozenset({demand} if demand else ()))

    def can(self, skill: str, objects: Sequence[str]) -> bool:
        """Whether the whole team can make the call (what it asks depends on its skill and first object)."""
        key = (skill, objects[0] if objects else "")
        if key not in self._memo:
            self._memo[key] = can_do(self.team, self.need(skill, objects))
        return self._memo[key]

    def why_not(self, skill: str, objects: Sequence[str]) -> list[str]:
        """Why the whole team cannot make the call (see :func:`shortfall`)."""
        return shortfall(self.team, self.need(skill, objects), lifted=f"the {objects[0]}" if objects else "")


def feasible_teams(team: Sequence[Robot], need: Need) -> list[tuple[int, ...]] | None:
    """Sets of team indices (in increasing order) that can do the need; None when the team is too big to list."""
    if len(team) > EXACT_COALITIONS:
        return None
    return [c for n in range(1, len(team) + 1) for c in combinations(range(len(team)), n)
            if can_do([team[i] for i in c], need)]


def minimal_teams(teams: list[tuple[int, ...]] | None) -> list[tuple[int, ...]] | None:
    """The teams none of whose members could be left out: a robot the sub-task does not need stays free
    for another one (a coalition names no more robots than the work asks for)."""
    return None if teams is None else minimal_lists(teams, named=0)


def minimal_lists(lists: list[tuple[int, ...]], named: int) -> list[tuple[int, ...]]:
    """The robot lists none of whose unnamed robots could be left out. Robots past the ``named`` slots a
    function calls by index only join its whole-list steps, so a list has them only where they are needed."""
    able = set(lists)
    return [o for o in lists if not any(o[:k] + o[k + 1:] in able for k in range(named, len(o)))]


def shortest_list(whole: bool, max_index: int, team_size: int, *, notional: bool) -> int:
    """How many robots a function's list needs: enough for its highest ``robot_list[i]``. A function
    that names the whole ``robot_list`` may be run by part of the team when each list is dry-run with
    the team's own robots (a restated allocation); a notional dry run moves every slot for such a
    step, so there it takes them all."""
    return team_size if whole and notional else max(1, max_index + 1)


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


def one_robot_suffices(team: Sequence[Robot], steps: Sequence[Step]) -> bool:
    """Whether a function of these steps is one robot's work whoever is free: one robot of the team can do every
    step, and every robot with a step's skill can do that step alone, so a team would pool nothing (no load, no
    place's capacity) and no robot list of two is ever the least one that works."""
    return any(all(_step_ok([robot], step) for step in steps) for robot in team) and \
        all(_step_ok([robot], step) for step in steps for robot in team if step.skill in robot.skills)


def _step_ok(listed: Sequence[Robot], step: Step) -> bool:
    actors = listed if step.slot is None else [listed[step.slot]]
    demand = step.demand
    if demand is not None and not all(demand.place.reachable_by(r) for r in actors):
        return False
    return can_do(actors, Need(frozenset({step.skill}), step.mass, frozenset({demand} if demand else ())))
