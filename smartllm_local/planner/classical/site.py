"""A site domain's rules as a planning domain: where robots stand, what is covered and photographed.

Written from the domain file alone (its skills' effects, the robots' kinds and capacities, each place's
reach and area), so any site domain, the starter and a user's included, gets it. Each action is the site
executor's call (:mod:`...executor.site`) with the same outcome, nothing left out:

- a call is made by a *team*, any group of the task's robots (an object of type ``team``; a single robot
  is a team of one): it has a skill when a member has it, and goes only where every member can;
- ``move`` takes the team to any place; ``patrol`` to a region it then covers, where the capacity the
  skill pools, added over the members with the skill, reaches the region's area;
- ``photograph`` moves nobody: a member with the skill must stand within its camera range of the object.

A sum of capacities is not a PDDL expression, so what each team pools, and which places lie within each
robot's camera range of where, are static facts of the problem, computed here from the domain file
with the executor's own rules (:func:`...executor.site.why_not`, :func:`...domain.pooled`).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

from unified_planning.model import Fluent, InstantaneousAction, MinimizeActionCosts, Object, Problem, Variable
from unified_planning.model.fnode import FNode
from unified_planning.shortcuts import And, BoolType, Equals, Exists, Forall, Implies, IntType, Not, Or, UserType

from ...domain import Domain, Place, pooled
from ...robots import Robot
from ...scoring import Condition, normalize_name
from ...skills import Skill
from .problem import BuiltProblem, PlanningTask, Unreachable, pddl_name

PLACE = UserType("place")
#: The site's kinds of entry as types: a move goes to any place, a patrol to a region, a picture of an object.
KIND_TYPES = {"location": UserType("location", PLACE), "region": UserType("region", PLACE),
              "object": UserType("site_object", PLACE)}  # "object" is PDDL's own root type
ROBOT = UserType("robot")
TEAM = UserType("team")
EFFECT_TYPES = {"move": PLACE, "patrol": KIND_TYPES["region"], "photograph": KIND_TYPES["object"]}
#: A goal state, the effect that makes it true, and the kind of place it takes ("" for any). The team is returned
#: where it starts before any call, and by any call that moves it: no one effect.
GOAL_EFFECTS = {"COVERED": ("patrol", "region"), "PHOTOGRAPHED": ("photograph", "object"), "RETURNED": ("", "")}
CAMERA = "camera_range"  # the capacity the executor measures a picture's distance against
MAX_TEAM = 10  # robots in a task: its teams are every group of them (2^n - 1 objects)


def fluents(domain: Domain) -> dict[str, Fluent]:
    """Every predicate: the states calls change, and the static facts the domain file fixes."""
    b = BoolType()
    region, target = KIND_TYPES["region"], KIND_TYPES["object"]
    table = {
        "at": Fluent("at", b, r=ROBOT, p=PLACE),  # where the robot stands
        "covered": Fluent("covered", b, g=region),
        "photographed": Fluent("photographed", b, o=target),
        "member": Fluent("member", b, r=ROBOT, t=TEAM),
        "reaches": Fluent("reaches", b, r=ROBOT, p=PLACE),  # the place's reach admits the robot's kind
        "has_camera": Fluent("has_camera", b, r=ROBOT),  # a camera_range above 0
        # from p, the object o is within r's camera range
        "in_range": Fluent("in_range", b, r=ROBOT, p=PLACE, o=target),
    }
    for skill in domain.catalogue.skills:
        table[skill_fluent(skill)] = Fluent(skill_fluent(skill), b, r=ROBOT)
        if skill in domain.pools:  # the team's members with the skill pool enough of its capacity for the region
            table[pool_fluent(skill)] = Fluent(pool_fluent(skill), b, t=TEAM, g=region)
    return table


def skill_fluent(skill: str) -> str:
    return f"skill_{skill}"


def pool_fluent(skill: str) -> str:
    return f"pools_enough_{skill}"


def action(skill: Skill, effect: str, f: dict[str, Fluent]) -> InstantaneousAction:
    """The call of ``skill`` by a team on a place, as the site executor performs it."""
    act = InstantaneousAction(skill.name, t=TEAM, p=EFFECT_TYPES[effect])
    t, p = act.parameter("t"), act.parameter("p")
    r, q = Variable("r", ROBOT), Variable("q", PLACE)
    skilled = And(f["member"](r, t), f[skill_fluent(skill.name)](r))
    act.add_precondition(Exists(skilled, r))
    act.add_precondition(Forall(Implies(f["member"](r, t), f["reaches"](r, p)), r))
    if effect == "photograph":
        act.add_precondition(Exists(And(skilled, f["has_camera"](r)), r))
        act.add_precondition(Exists(And(skilled, f["at"](r, q), f["in_range"](r, q, p)), r, q))
        act.add_effect(f["photographed"](p), True)
        return act
    if effect == "patrol":
        act.add_precondition(f[pool_fluent(skill.name)](t, p))
        act.add_effect(f["covered"](p), True)
    act.add_effect(f["at"](r, q), False, And(f["member"](r, t), Not(Equals(q, p))), forall=[r, q])
    act.add_effect(f["at"](r, p), True, f["member"](r, t), forall=[r])
    return act


def teams(size: int) -> list[tuple[int, ...]]:
    """Every group of a task's robots that a call can name, by team index."""
    return [c for k in range(1, size + 1) for c in itertools.combinations(range(size), k)]


def site_planning_task(domain: Domain, team: Sequence[Robot], conditions: Sequence[Condition],
                       name: str = "task") -> PlanningTask:
    """The problem of reaching ``conditions`` on ``domain``'s site with ``team``, every robot at the start.

    Raises:
        Unreachable: a condition no call of the domain can make true (naming it and why).
    """
    if len(team) > MAX_TEAM:
        raise Unreachable(f"the planner takes teams of up to {MAX_TEAM} robots on a site, and this one has "
                          f"{len(team)}")
    f = fluents(domain)
    problem = BuiltProblem(name)
    for fluent in f.values():
        problem.add_fluent(fluent, default_initial_value=False)
    size = Fluent("size", IntType(), t=TEAM)  # what a call by the team costs: its robots' time
    problem.add_fluent(size, default_initial_value=1)
    skill_of = {}
    costs = {}
    for skill in domain.catalogue.skills.values():
        act = action(skill, domain.effects[skill.name], f)
        problem.add_action(act)
        costs[act] = size(act.parameter("t"))
        skill_of[skill.name] = skill.name
    problem.add_quality_metric(MinimizeActionCosts(costs))
    taken: set[str] = set()
    places = {p.name: Object(pddl_name(p.name, taken), KIND_TYPES[p.kind]) for p in domain.places.values()}
    robots = [Object(pddl_name(f"robot{i}", taken), ROBOT) for i in range(len(team))]
    groups = {members: Object(pddl_name("team" + "and".join(map(str, members)), taken), TEAM)
              for members in teams(len(team))}
    problem.add_objects([*places.values(), *robots, *groups.values()])
    for members, group in groups.items():
        problem.set_initial_value(size(group), len(members))
    _initial_state(problem, f, domain, team, places, robots, groups)
    problem.add_goal(And(*(_condition(f, domain, c, places, robots) for c in conditions)))
    robot_names = {o.name: i for i, o in enumerate(robots)}
    return PlanningTask(problem.built(), {o.name: place for place, o in places.items()}, robot_names,
                        {s.name: s.action for s in domain.catalogue.skills.values()}, skill_of,
                        teams={o.name: members for members, o in groups.items()})


def _initial_state(problem: Problem, f: dict[str, Fluent], domain: Domain, team: Sequence[Robot],
                   places: dict[str, Object], robots: Sequence[Object],
                   groups: dict[tuple[int, ...], Object]) -> None:
    def true(fluent: str, *args: Object) -> None:
        problem.set_initial_value(f[fluent](*args), True)

    site = list(domain.places.values())
    for robot, member in zip(robots, team):
        true("at", robot, places[domain.start])
        for skill in member.skills:
            true(skill_fluent(skill), robot)
        camera = member.capacity(CAMERA) if CAMERA in domain.capacities else 0.0
        if camera > 0:
            true("has_camera", robot)
        for place in site:
            if place.reachable_by(member):
                true("reaches", robot, places[place.name])
            for target in (p for p in site if p.kind == "object"):
                if math.dist(place.at, target.at) <= camera:
                    true("in_range", robot, places[place.name], places[target.name])
    for members, group in groups.items():
        for m in members:
            true("member", robots[m], group)
        for skill, capacity in domain.pools.items():
            total = pooled([team[m] for m in members], skill, capacity)
            for region in (p for p in site if p.kind == "region" and total >= p.area):
                true(pool_fluent(skill), group, places[region.name])


def _condition(f: dict[str, Fluent], domain: Domain, condition: Condition, places: dict[str, Object],
               robots: Sequence[Object]) -> FNode:
    """A goal condition as the scorer reads it from the site: a region covered, an object photographed, the
    whole team standing where the place is (at any place at the same point)."""
    place = _goal_place(domain, condition)
    if condition.state == "COVERED":
        return f["covered"](places[place.name])
    if condition.state == "PHOTOGRAPHED":
        return f["photographed"](places[place.name])
    same = [places[p.name] for p in domain.places.values() if p.at == place.at]
    return And(*(Or(*(f["at"](r, q) for q in same)) for r in robots))


def _goal_place(domain: Domain, condition: Condition) -> Place:
    """The place a condition names, where some call of the domain can give it its state."""
    what = condition.describe()
    place = next((p for p in domain.places.values() if normalize_name(p.name) == normalize_name(condition.subject)),
                 None)
    if place is None:
        raise Unreachable(f"`{what}`: there is no {condition.subject!r} on the site {domain.site}")
    if condition.state not in GOAL_EFFECTS:
        raise Unreachable(f"`{what}`: a site's goals are a region covered, an object photographed or the team "
                          "returned to a place")
    effect, kind = GOAL_EFFECTS[condition.state]
    if kind and place.kind != kind:
        raise Unreachable(f"`{what}`: {place.name} is a {place.kind}, and only a {kind} can be {condition.state}")
    if effect and effect not in domain.effects.values():
        raise Unreachable(f"`{what}`: no skill of the {domain.name} domain has the effect {effect}")
    return place
