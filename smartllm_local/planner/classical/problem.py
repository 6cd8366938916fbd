"""A task as a planning problem: the scene's objects in the state the executor starts from, the team, the goal.

The objects are those the goal can involve (:func:`relevant`): the types it names, their pieces, the
receptacles that hold them, and the tools and sources its states need (a knife to slice, a fridge to
chill, a faucet to fill). Every other object only adds actions the planner would ground and never use.
The goal is the scorer's (:mod:`...scoring`): each condition holds when some object of its type does,
so a condition is a disjunction over the scene's candidates.
"""

from __future__ import annotations

import re
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field
from itertools import permutations
from typing import Any

from unified_planning.model import Object, Problem, Variable
from unified_planning.model.fnode import FNode
from unified_planning.shortcuts import And, Exists, Forall, Not, Or

from ...executor.dry_run import DryRun
from ...executor.team_actions import KNIVES
from ...robots import Robot
from ...scoring import Condition, normalize_name
from ...skills import SkillSet, has_affordance
from ...world.object_types import (
    COLD_SOURCES,
    HEAT_SOURCES,
    OPEN_TOPPED,
    SLICE_PARENT,
    SLICE_RESULTS,
    WATER_BASINS,
    base_type,
)
from ...world.rules import basins_of, is_heating, make_pieces, refuses
from .model import (
    AFFORDANCE_FLUENTS,
    FIXTURE,
    ITEM,
    ROBOT,
    THING,
    Vocabulary,
    add_fluents,
    skill_actions,
    skill_fluent,
    vocabulary,
)

_MASS_TOLERANCE = 1e-6  # as the executor's (scene masses are float32)
#: The states whose goal needs a tool or source beyond the objects it names.
_STATE_NEEDS: dict[str, frozenset[str]] = {
    "HOT": HEAT_SOURCES | {"StoveKnob"}, "COOKED": HEAT_SOURCES | {"StoveKnob"}, "COLD": COLD_SOURCES,
    "CLEAN": WATER_BASINS | {"Faucet"}, "FILLED": WATER_BASINS | {"Faucet", "CoffeeMachine"},
    "ON": frozenset({"StoveKnob"}), "OFF": frozenset({"StoveKnob"}),
}


class BuiltProblem(Problem):
    """A planning problem whose kind is computed once, when :meth:`built` says it is complete: Unified Planning
    computes a problem's kind on every access (seven times in one search with its PDDL, 0.02-0.2 s each), and a
    :class:`PlanningTask`'s problem is not changed once made."""

    def __init__(self, name: str):
        super().__init__(name)
        self._built_kind: Any = None

    def built(self) -> BuiltProblem:
        self._built_kind = super().kind
        return self

    @property
    def kind(self) -> Any:
        return self._built_kind if self._built_kind is not None else super().kind


class Unreachable(Exception):
    """A goal condition no object of the scene can ever meet (said before any search)."""


@dataclass
class PlanningTask:
    """A problem and how its names map back: things to objectIds, robots to team indices."""

    problem: Problem
    things: dict[str, str]  # planning name -> objectId
    robots: dict[str, int]  # planning name -> team index
    actions: dict[str, str]  # skill -> the AI2-THOR action it performs
    skill_of: dict[str, str]  # planning action -> the skill a plan calls for it
    teams: dict[str, tuple[int, ...]] = field(default_factory=dict)  # a site's: planning name -> team indices


def pddl_name(text: str, taken: set[str]) -> str:
    """A PDDL name: letters and digits only (a grounder joins an action's and its arguments' names with _)."""
    base = re.sub(r"[^A-Za-z0-9]+", "", text).lower() or "thing"
    name, k = base, 1
    while name in taken:
        k += 1
        name = f"{base}x{k}"
    taken.add(name)
    return name


def with_future_pieces(objects: Sequence[Mapping[str, Any]]) -> tuple[list[dict[str, Any]], set[str]]:
    """The objects and the pieces cutting them would make (rules.make_pieces), and the ids of those pieces."""
    table = [dict(o) for o in objects]
    ids = {o["objectId"] for o in table}
    future: set[str] = set()
    for whole in objects:
        if whole["objectType"] in SLICE_RESULTS and not whole.get("isSliced") and not whole.get("isBroken"):
            for piece in make_pieces(dict(whole)):
                if piece["objectId"] not in ids:
                    table.append(piece)
                    future.add(piece["objectId"])
    return table, future


def relevant(objects: Sequence[Mapping[str, Any]], conditions: Sequence[Condition]) -> list[Mapping[str, Any]]:
    """The objects the goal can involve: its types (and their pieces or wholes; the pieces of a thing cut already,
    which the scorer counts as it), the tools and sources its states need, every receptacle holding any of those (to
    be opened), and what a receptacle to be emptied holds (not what the places it may go to hold: nothing there need
    move)."""
    names = {normalize_name(n) for c in conditions for n in (c.subject, c.item) if n}
    wanted = set(names)
    cut = {normalize_name(c.subject) for c in conditions if c.state == "SLICED"}
    cut |= {o["objectType"].lower() for o in objects if o.get("isSliced")} & names  # cut already: its pieces are it
    for kind in {o["objectType"] for o in objects}:
        if kind in SLICE_PARENT and (kind.lower() in names or SLICE_PARENT[kind].lower() in cut):
            wanted |= {kind.lower(), SLICE_PARENT[kind].lower()}  # the pieces, and the whole they come from
    for c in conditions:
        wanted |= {t.lower() for t in _STATE_NEEDS.get(c.state or "", ())}
        if c.state == "EMPTY":  # what is in it must go somewhere: any receptacle that is never shut
            wanted |= {o["objectType"].lower() for o in objects if o.get("receptacle") and not o.get("openable")}
    if any(k in wanted for k in (p.lower() for p in SLICE_PARENT)):  # pieces to be cut: a knife
        wanted |= {k.lower() for k in KNIVES}
    by_id = {o["objectId"]: o for o in objects}
    chosen = {o["objectId"] for o in objects if o["objectType"].lower() in wanted}
    chosen |= {o["objectId"] for o in objects if any(s in chosen for s in o.get("controlledObjects") or ())}
    emptied = {o["objectId"] for o in objects if o["objectType"].lower() in
               {normalize_name(c.subject) for c in conditions if c.state == "EMPTY"}}
    chosen |= {o["objectId"] for o in objects if set(o.get("parentReceptacles") or ()) & emptied}
    stack = list(chosen)
    while stack:  # the holders of holders
        for parent in by_id[stack.pop()].get("parentReceptacles") or ():
            if parent in by_id and parent not in chosen:
                chosen.add(parent)
                stack.append(parent)
    return [o for o in objects if o["objectId"] in chosen]


def planning_task(dry: DryRun, team: Sequence[Robot], skills: SkillSet, conditions: Sequence[Condition],
                  name: str = "task", members: Sequence[int] | None = None,
                  hands_free: bool = False, leave_out: Collection[str] = ()) -> PlanningTask:
    """The problem of reaching ``conditions`` with ``team`` from the dry run's current state. ``members``: the
    dry run's robots the team's are, each starting as that one stands (by what it sees, holding what it holds);
    none given, the team starts with empty hands, by nothing. ``hands_free``: every robot ends holding nothing.
    ``leave_out``: objects the plan may not use (the fixtures of a type a plan's robot does not go to), save those
    holding what the goal involves.

    Raises:
        Unreachable: a condition that no object of the scene can meet (naming it).
    """
    v = vocabulary(skills)
    problem = BuiltProblem(name)
    add_fluents(problem, v)
    skill_of: dict[str, str] = {}
    for skill in skills.values():
        for action in skill_actions(skill, v, len(team)):
            problem.add_action(action)
            skill_of[action.name] = skill.name
    table, future = with_future_pieces(dry.objects)
    held = [dry.world.holding(m) for m in members or ()]
    kept = {h["objectId"] for h in held if h is not None}
    kept |= {o["objectId"] for o in relevant(table, conditions)}
    chosen = [o for o in table if o["objectId"] in kept]
    holders = {p for o in chosen for p in o.get("parentReceptacles") or ()}
    chosen = [o for o in chosen if o["objectId"] not in leave_out or o["objectId"] in holders]
    taken: set[str] = set()
    things = {o["objectId"]: Object(pddl_name(o["objectType"] + str(k), taken),
                                    ITEM if o.get("pickupable") else FIXTURE)
              for k, o in enumerate(chosen)}
    robots = [Object(pddl_name(f"robot{i}", taken), ROBOT) for i in range(len(team))]  # robots[i] of a plan
    problem.add_objects([*things.values(), *robots])
    _initial_state(problem, v, dry, chosen, things, future, team)
    for robot, member in zip(robots, members or ()):
        _stands(problem, v, dry, member, robot, things)
    goal = And(*(_condition(v, c, chosen, things, future) for c in conditions),
               *(v.free(robot) for robot in robots if hands_free))
    if problem.environment.simplifier.simplify(goal).is_false():  # (which no PDDL file can say)
        raise Unreachable("the goal contradicts itself: no state of this scene meets all of its conditions at once")
    problem.add_goal(goal)
    return PlanningTask(problem.built(), {o.name: oid for oid, o in things.items()},
                        {o.name: i for i, o in enumerate(robots)}, {s.name: s.action for s in skills.values()},
                        skill_of)


def _initial_state(problem: Problem, v: Vocabulary, dry: DryRun, chosen: Sequence[Mapping[str, Any]],
                   things: Mapping[str, Object], future: set[str], team: Sequence[Robot]) -> None:
    by_id = {o["objectId"]: o for o in chosen}
    table = {o["objectId"]: dict(o) for o in dry.objects}

    def true(fluent: str, *args: Object) -> None:
        problem.set_initial_value(v.fluents[fluent](*args), True)

    for oid, o in by_id.items():
        t, kind = things[oid], o["objectType"]
        facts = {
            **{a: has_affordance(o, a) for a in AFFORDANCE_FLUENTS},
            "can_fill": o.get("canFillWithLiquid"), "cookable": o.get("cookable"), "knife": kind in KNIVES,
            "shuts": o.get("openable") and kind not in OPEN_TOPPED, "microwave": kind == "Microwave",
            "heats_when_on": kind in ("Toaster", "CoffeeMachine"), "coffee_maker": kind == "CoffeeMachine",
            "mug": kind == "Mug", "chills": kind in COLD_SOURCES, "cracks": kind in SLICE_RESULTS,
            "present": oid not in future and not (o.get("isSliced") and kind in SLICE_RESULTS),
            "is_open": o.get("isOpen"), "is_on": o.get("isToggled"), "dirty": o.get("isDirty"),
            "broken": o.get("isBroken"), "sliced": o.get("isSliced"), "hot": o.get("temperature") == "Hot",
            "cold": o.get("temperature") == "Cold", "cooked": o.get("isCooked"),
            "filled": o.get("isFilledWithLiquid"), "held": o.get("isPickedUp"),
            "heating": kind in HEAT_SOURCES and oid in table and is_heating(table, table[oid]),
            "rinsing": kind in WATER_BASINS and any(
                f.get("isToggled") and oid in {b["objectId"] for b in basins_of(table, f)}
                for f in table.values() if f["objectType"] == "Faucet"),
        }
        for fluent, value in facts.items():
            if value:
                true(fluent, t)
        for parent in () if oid in future else o.get("parentReceptacles") or ():  # a piece lies only once cut
            if parent in things:
                true("inside", t, things[parent])
        for burner in o.get("controlledObjects") or ():
            if burner in things:
                true("controls", t, things[burner])
        if kind == "Faucet":
            for basin in basins_of(table, o):
                if basin["objectId"] in things:
                    true("rinses", t, things[basin["objectId"]])
        whole = oid.rsplit("|", 1)[0]
        if kind in SLICE_PARENT and whole in things:
            true("piece_of", t, things[whole])
        if o.get("pickupable"):
            for rid, receptacle in by_id.items():
                if receptacle.get("receptacle") and rid != oid and refuses(o, receptacle) is None:
                    true("fits", t, things[rid])
    _robots(problem, v, dry, by_id, things, team)


def _robots(problem: Problem, v: Vocabulary, dry: DryRun, by_id: Mapping[str, Mapping[str, Any]],
            things: Mapping[str, Object], team: Sequence[Robot]) -> None:
    """Each robot's skills, its free hand, and what it can lift (alone, or with one teammate)."""
    robots = list(problem.objects(ROBOT))
    table = {o["objectId"]: o for o in dry.objects}
    for robot, member in zip(robots, team):
        for skill in member.skills:
            if skill_fluent(skill) in v.fluents:
                problem.set_initial_value(v.fluents[skill_fluent(skill)](robot), True)
        problem.set_initial_value(v.free(robot), True)  # a dry run starts with empty hands
    movable = sum(float(o.get("mass") or 0.0) for o in table.values() if o.get("pickupable"))
    for oid, o in by_id.items():
        if not o.get("pickupable"):
            continue
        mass = _carried_mass(table, o)
        lifts = _lifts(problem, v, robots, team, things[oid], mass)
        if any(capacity < mass + movable for capacity in lifts):  # a lift that every other thing put in could stop
            problem.set_initial_value(v.tight(things[oid]), True)


def _lifts(problem: Problem, v: Vocabulary, robots: Sequence[Object], team: Sequence[Robot], thing: Object,
           mass: float) -> list[float]:
    """Set who lifts the thing, alone, by two or (where no two do) by three, and give the capacity of each lift."""
    capacity = [r.mass_capacity for r in team]
    lifts: list[float] = []
    for i, robot in enumerate(robots):
        if capacity[i] + _MASS_TOLERANCE >= mass:
            problem.set_initial_value(v.lifts(robot, thing), True)
            lifts.append(capacity[i])
        for j, helper in enumerate(robots):
            if j != i and capacity[i] + capacity[j] + _MASS_TOLERANCE >= mass:
                problem.set_initial_value(v.lifts_together(robot, helper, thing), True)
                lifts.append(capacity[i] + capacity[j])
    if lifts:
        return lifts
    for i, j, k in permutations(range(len(robots)), 3):
        if j < k and capacity[i] + capacity[j] + capacity[k] + _MASS_TOLERANCE >= mass:
            problem.set_initial_value(v.lifts_by_three(robots[i], robots[j], robots[k], thing), True)
            lifts.append(capacity[i] + capacity[j] + capacity[k])
    return lifts


def _stands(problem: Problem, v: Vocabulary, dry: DryRun, member: int, robot: Object,
            things: Mapping[str, Object]) -> None:
    """A robot that has acted already: by what its dry-run member sees, holding what it holds."""
    for oid, thing in things.items():
        if dry.world.sees(member, oid):
            problem.set_initial_value(v.at(robot, thing), True)
    held = dry.world.holding(member)
    if held is not None and held["objectId"] in things:
        problem.set_initial_value(v.holding(robot, things[held["objectId"]]), True)
        problem.set_initial_value(v.free(robot), False)


def _carried_mass(table: Mapping[str, Mapping[str, Any]], obj: Mapping[str, Any]) -> float:
    """Its mass and that of what it holds now, nested (TeamWorld._carried_mass)."""
    total, stack, seen = float(obj.get("mass") or 0.0), list(obj.get("receptacleObjectIds") or ()), set()
    while stack:
        oid = stack.pop()
        if oid in seen or oid not in table:
            continue
        seen.add(oid)
        total += float(table[oid].get("mass") or 0.0)
        stack.extend(table[oid].get("receptacleObjectIds") or ())
    return total


def _state_test(v: Vocabulary, state: str, o: Mapping[str, Any], t: Object) -> FNode | None:
    """The scorer's test of one state on one object (scoring._STATE_TESTS), or None where it can never pass."""
    switchable = o.get("toggleable") or o["objectType"] == "StoveBurner"
    tests: dict[str, tuple[bool, FNode]] = {
        "ON": (switchable, v.is_on(t)), "OFF": (switchable, Not(v.is_on(t))),
        "OPENED": (o.get("openable"), v.is_open(t)), "CLOSED": (o.get("openable"), Not(v.is_open(t))),
        "HOT": (True, v.hot(t)), "COLD": (True, v.cold(t)), "COOKED": (True, v.cooked(t)),
        "BROKEN": (True, v.broken(t)), "PICKED": (True, v.held(t)), "DIRTY": (True, v.dirty(t)),
        "CLEAN": (o.get("dirtyable"), Not(v.dirty(t))), "FILLED": (True, v.filled(t)),
    }
    if state == "EMPTY":
        x = Variable("x", THING)
        return Forall(Not(v.inside(x, t)), x) if o.get("receptacle") else None
    possible, test = tests[state]
    return test if possible else None


def _condition(v: Vocabulary, condition: Condition, objects: Sequence[Mapping[str, Any]],
               things: Mapping[str, Object], future: set[str]) -> FNode:
    """One condition, as the scorer checks it (scoring.condition_holds), over the chosen objects."""
    subject = normalize_name(condition.subject)

    def kept(oid: str, test: FNode) -> FNode:  # a piece not cut yet is in no final table
        return And(v.present(things[oid]), test) if oid in future else test

    def matches(o: Mapping[str, Any], wanted: str) -> bool:
        return wanted in (o["objectType"].lower(), base_type(o["objectType"]).lower())

    options: list[FNode] = []
    if condition.state == "SLICED":
        pieces = {SLICE_RESULTS[t][0].lower() for t in SLICE_RESULTS if t.lower() == subject}
        for o in objects:
            t = things[o["objectId"]]
            if o["objectType"].lower() == subject and o.get("sliceable"):
                options.append(v.sliced(t))
            elif o["objectType"].lower() in pieces:
                options.append(kept(o["objectId"], v.present(t)))
    elif condition.state is not None:
        for o in objects:
            test = _state_test(v, condition.state, o, things[o["objectId"]]) if matches(o, subject) else None
            if test is not None:
                options.append(kept(o["objectId"], test))
    else:
        item = normalize_name(condition.item or "")
        holders = [things[o["objectId"]] for o in objects if o["objectType"].lower() == subject and o.get("receptacle")]
        m = Variable("m", THING)
        for o in (o for o in objects if matches(o, item)):
            x = things[o["objectId"]]
            for r in holders:  # the holder between as a variable: one disjunct per holder took the translator 40 s
                options.append(kept(o["objectId"], Or(v.inside(x, r), Exists(And(v.inside(x, m), v.inside(m, r)), m))))
    if not options:
        raise Unreachable(f"no object of this scene can meet `{condition.describe()}`")
    return Or(*options)
