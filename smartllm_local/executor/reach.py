"""Which goal conditions a team can never meet in an AI2-THOR scene, whatever the plan, and why.

A condition needs certain AI2-THOR actions from the team: a slice needs ``SliceObject`` and a knife picked up,
an object put in a closed fridge needs ``OpenObject``, ``PickupObject`` and ``PutObject``. Where no way of
meeting it is within the actions the team's skills perform (or, for an object to be moved, within what the
whole team lifts together), and it does not hold already, no plan of this team meets it. Sound, not
complete: a condition named here is out of reach; one not named may still be (a state this check does not
judge, a door the robots cannot get to). What a planner may refuse on before writing a step.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from ..robots import Robot, team_lift
from ..scoring import Condition, condition_holds, containment, normalize_name
from ..skills import SkillSet
from ..world.object_types import HEAT_SOURCES, base_type

_MOVE = frozenset({"PickupObject", "PutObject"})
#: The ways to each state, each a set of actions that together can give it (any one way suffices).
_WAYS: dict[str, tuple[frozenset[str], ...]] = {
    "SLICED": (frozenset({"SliceObject", "PickupObject"}),),  # the knife is picked up first
    "ON": (frozenset({"ToggleObjectOn"}),),
    "OFF": (frozenset({"ToggleObjectOff"}),),
    "OPENED": (frozenset({"OpenObject"}),),
    "CLOSED": (frozenset({"CloseObject"}),),
    "PICKED": (frozenset({"PickupObject"}),),
    "COLD": (_MOVE,),  # into a fridge
    "BROKEN": (frozenset({"BreakObject"}), frozenset({"PickupObject", "ThrowObject"}),
               frozenset({"PickupObject", "DropHandObject"})),
}


def unattainable(conditions: Sequence[Condition], team: Sequence[Robot], skills: SkillSet,
                 objects: Sequence[Mapping[str, Any]]) -> list[str]:
    """The conditions (of ``conditions``, over a scene's initial ``objects``) no plan of ``team`` can meet, each
    with why, in the skill names of ``skills``."""
    actions = {skills[s].action for r in team for s in r.skills if s in skills}
    inside = containment(objects)
    problems = []
    for condition in conditions:
        if condition_holds(condition, objects, inside):
            continue
        ways = _ways(condition, objects)
        if ways and not any(way <= actions for way in ways):
            missing = min((way - actions for way in ways), key=len)
            names = ", ".join(_skill_names(sorted(missing), skills))
            problems.append(f"{condition.describe()} needs {names}, which no robot of the team has")
            continue
        heavy = _too_heavy(condition, team, skills, objects)
        if heavy:
            problems.append(heavy)
    return problems


def _ways(condition: Condition, objects: Sequence[Mapping[str, Any]]) -> tuple[frozenset[str], ...]:
    """The ways to meet a condition not yet met (none: this check does not judge it)."""
    if condition.state is None:  # an item into a receptacle: a closed one must be opened first
        held = [o for o in objects if _is(o, condition.subject)]
        shut = bool(held) and all(o.get("openable") and not o.get("isOpen") for o in held)
        return (_MOVE | {"OpenObject"},) if shut else (_MOVE,)
    if condition.state in ("HOT", "COOKED"):  # into a heat source, switched on unless one is on already
        running = any(base_type(o["objectType"]) in HEAT_SOURCES and o.get("isToggled") for o in objects)
        return (_MOVE if running else _MOVE | {"ToggleObjectOn"},)
    if condition.state == "CLEAN":  # cleaned, or (a thing that can be carried) rinsed under a running faucet
        carried = any(_is(o, condition.subject) and o.get("pickupable") for o in objects)
        return (frozenset({"CleanObject"}), *((_MOVE | {"ToggleObjectOn"},) if carried else ()))
    return _WAYS.get(condition.state, ())


def _too_heavy(condition: Condition, team: Sequence[Robot], skills: SkillSet,
               objects: Sequence[Mapping[str, Any]]) -> str:
    """Why the thing a containment moves is too heavy for the whole team together ("" if it is not, or if no robot
    picks things up: that is a missing skill)."""
    if condition.state is not None or not condition.item:
        return ""
    masses = [float(o.get("mass") or 0.0) for o in objects if _is(o, condition.item)]
    if not masses or not any(r.skills & skills.lifting for r in team):
        return ""
    pooled = team_lift(team)
    if min(masses) > pooled:
        return (f"{condition.describe()} needs {condition.item} ({min(masses):g} kg) lifted, and the team lifts "
                f"{pooled:g} kg together")
    return ""


def _is(obj: Mapping[str, Any], name: str) -> bool:
    wanted = normalize_name(name)
    return obj["objectType"].lower() == wanted or base_type(obj["objectType"]).lower() == wanted


def _skill_names(actions: Sequence[str], skills: SkillSet) -> list[str]:
    """Each action as the catalogue's skill that performs it (the action's own name where none does)."""
    by_action: dict[str, str] = {}
    for skill in skills.values():
        by_action.setdefault(skill.action, skill.name)
    return [by_action.get(a, a) for a in actions]
