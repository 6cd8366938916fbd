"""A sequential plan as sub-tasks and threads: one sub-task per independent part, each on robots of its own.

Two steps belong to the same part when they touch a common object: one they name, one that holds
what they name at that point of the plan (a fridge to be opened before what is in it is taken), or
one a switch they press works on (a StoveKnob's burner, a Faucet's basin). Parts therefore share no
object, and where they share no robot either they run in parallel; within a part the steps keep the
planner's order. Fast Downward minimises steps, not time, and may give every step to one robot: a
part is moved to robots no earlier part uses where the planning model (Unified Planning's
simulator) says the moved steps stay valid, else it keeps its robots and joins the part that
shares them, to run one after the other.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

from unified_planning.plans import ActionInstance
from unified_planning.shortcuts import SequentialSimulator

from ...world.object_types import SLICE_RESULTS
from ...world.rules import basins_of
from .model import ROBOT
from .problem import PlanningTask
from .search import Step

_TRIES = 24  # robot assignments tried per part (each a check of the whole plan in the model)


@dataclass
class Part:
    """A sub-task: plan positions (in order) and the robots (team indices) they use."""

    indices: list[int]
    robots: list[int]


def _holders(objects: Sequence[Mapping[str, Any]]) -> dict[str, set[str]]:
    return {o["objectId"]: set(o.get("parentReceptacles") or ()) for o in objects}


def linked_objects(objects: Sequence[Mapping[str, Any]]) -> dict[str, set[str]]:
    """What a switch works on: a StoveKnob's burners, a Faucet's basins (within reach of its water)."""
    table = {o["objectId"]: dict(o) for o in objects}
    links: dict[str, set[str]] = {}
    for o in objects:
        linked = set(o.get("controlledObjects") or ())
        if o["objectType"] == "Faucet":
            linked |= {b["objectId"] for b in basins_of(table, table[o["objectId"]])}
        if linked:
            links[o["objectId"]] = linked
    return links


def touched(steps: Sequence[Step], objects: Sequence[Mapping[str, Any]]) -> list[set[str]]:
    """The objects each step depends on or changes (a piece's whole among them), following where things are
    as the plan moves them."""
    holders = _holders(objects)
    links = linked_objects(objects)
    ids = set(holders)
    out = []
    for step in steps:
        # a piece (<whole's id>|<Derived>_<k>) depends on the step that cut its whole
        named = [*step.objects, *(oid.rsplit("|", 1)[0] for oid in step.objects if oid.rsplit("|", 1)[0] in ids)]
        names = set(named)
        for oid in named:
            names |= links.get(oid, set())
            stack = list(holders.get(oid, ()))
            while stack:
                parent = stack.pop()
                if parent not in names:
                    names.add(parent)
                    stack.extend(holders.get(parent, ()))
        out.append(names)
        if step.skill and step.objects:
            _move(step, holders)
    return out


def _move(step: Step, holders: dict[str, set[str]]) -> None:
    """Where things are after a step (enough to follow containment: puts, pick-ups, cut pieces)."""
    first = step.objects[0]
    if len(step.objects) == 2 and step.action == "PutObject":
        holders[first] = {step.objects[1]}
    elif step.action == "PickupObject":
        holders[first] = set()
    elif step.action in ("SliceObject", "BreakObject"):  # its pieces lie where it lay
        for k in range(SLICE_RESULTS.get(first.split("|")[0], ("", 0))[1]):
            holders[f"{first}|{SLICE_RESULTS[first.split('|')[0]][0]}_{k}"] = set(holders.get(first, ()))


def parts(steps: Sequence[Step], objects: Sequence[Mapping[str, Any]]) -> list[Part]:
    """The plan's independent parts (by shared objects), in the order of their first steps."""
    reach = touched(steps, objects)
    parent = list(range(len(steps)))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    owner: dict[str, int] = {}
    for i, names in enumerate(reach):
        for name in names:
            if name in owner:
                parent[find(i)] = find(owner[name])
            else:
                owner[name] = i
    groups: dict[int, list[int]] = {}
    for i in range(len(steps)):
        groups.setdefault(find(i), []).append(i)
    return [Part(g, sorted({r for k in g for r in steps[k].robots})) for g in groups.values()]


def robot_parts(steps: Sequence[Step]) -> list[Part]:
    """The plan's parts where steps depend on their robots alone (a site's: a call changes where its robots
    stand and adds to what is covered or photographed): steps that share a robot, in plan order."""
    return _merge([Part([k], sorted(set(step.robots))) for k, step in enumerate(steps)])


def spread(task: PlanningTask, actions: Sequence[ActionInstance], steps: list[Step], found: list[Part],
           team_size: int) -> tuple[list[ActionInstance], list[Step], list[Part]]:
    """Give each part robots no earlier part uses, where the model says its steps stay valid; parts that
    still share a robot become one. Returns the plan with its robots changed and the final parts."""
    robot_objects = {i: o for o in task.problem.objects(ROBOT) for i in [task.robots[o.name]]}
    used: set[int] = set()
    actions, steps = list(actions), list(steps)
    for part in found:
        free = [i for i in range(team_size) if i not in used]
        if set(part.robots) & used:
            for chosen in itertools.islice(itertools.permutations(free, len(part.robots)), _TRIES):
                mapping = dict(zip(part.robots, chosen))
                trial = list(actions)
                for k in part.indices:
                    trial[k] = _recast(actions[k], mapping, robot_objects, task)
                if valid(task, trial):
                    actions = trial
                    for k in part.indices:
                        steps[k] = replace(steps[k], robots=tuple(mapping[r] for r in steps[k].robots))
                    part.robots = sorted(mapping.values())
                    break
        used |= set(part.robots)
    return actions, steps, _merge(found)


def _recast(action: ActionInstance, mapping: Mapping[int, int], robot_objects: Mapping[int, Any],
            task: PlanningTask) -> ActionInstance:
    params = []
    for p in action.actual_parameters:
        name = str(p)
        params.append(robot_objects[mapping[task.robots[name]]] if name in task.robots else p.object())
    return ActionInstance(action.action, params)


def valid(task: PlanningTask, actions: Sequence[ActionInstance]) -> bool:
    """Whether the plan is applicable from the initial state and ends with the goal met, in the model."""
    with SequentialSimulator(task.problem) as simulator:
        state = simulator.get_initial_state()
        for action in actions:
            if not simulator.is_applicable(state, action.action, action.actual_parameters):
                return False
            state = simulator.apply_unsafe(state, action.action, action.actual_parameters)
        return simulator.is_goal(state)


def _merge(found: list[Part]) -> list[Part]:
    """Parts that share a robot, as one (their steps in plan order)."""
    merged: list[Part] = []
    for part in found:
        joined = [m for m in merged if set(m.robots) & set(part.robots)]
        for m in joined:
            merged.remove(m)
        indices = sorted([*part.indices, *(k for m in joined for k in m.indices)])
        robots = sorted({*part.robots, *(r for m in joined for r in m.robots)})
        merged.append(Part(indices, robots))
    return sorted(merged, key=lambda p: p.indices[0])


def plan_text(steps: Sequence[Step], found: Sequence[Part], header: str) -> str:
    """The allocated plan: a function per part over its robots, a thread per part, all started, all joined."""
    lines = [f"# {line}" if line else "#" for line in header.splitlines()]
    lines += ["import threading", "", ""]
    for n, part in enumerate(found, start=1):
        local = {r: j for j, r in enumerate(part.robots)}
        lines.append(f"def part_{n}(robot_list):")
        for k in part.indices:
            step = steps[k]
            who = [f"robot_list[{local[r]}]" for r in step.robots]
            robots = who[0] if len(who) == 1 else f"[{', '.join(who)}]"
            objects = ", ".join(repr(o) for o in step.objects)
            lines.append(f"    {step.skill}({robots}, {objects})")
        lines += ["", ""]
    for n, part in enumerate(found, start=1):
        members = ", ".join(f"robots[{r}]" for r in part.robots)
        lines.append(f"t{n} = threading.Thread(target=part_{n}, args=([{members}],))")
    lines += [f"t{n}.start()" for n in range(1, len(found) + 1)]
    lines += [f"t{n}.join()" for n in range(1, len(found) + 1)]
    return "\n".join(lines) + "\n"
