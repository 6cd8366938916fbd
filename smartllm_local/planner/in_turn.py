"""A step nobody needs that alone makes sub-tasks run in turn, taken out before the teams are formed.

Asked to cut the bread and put the apple in the fridge, with one robot that slices, one that picks up and puts, and
one that does both and opens fridges, the 1.5B fetched a knife for the slice and then laid it down ("where it
stands"). Only the fridge's robot can both pick a knife up and drop it, and only it opens fridges, so the two
sub-tasks it started at once ran in turn: a transition the reference plan, where the picker holds the knife for
the slicer, does not make (RU 0 for a plan that met every goal).

So, for each block of sub-tasks the decomposition starts at once, the teams that could do each are sought, no robot
in two: a team has every skill its sub-task uses, lifts its heaviest thing, and for each thing one robot of it
picks up, has a member that does all that is done to the thing while held (the pick-up and the put, drop or
throw). Where no such teams exist, one step on a thing nobody asked for (the instruction does not name it and no
stated goal is about it), with the GoToObject steps right before it and the comments above, is taken out where
that alone lets them exist and the dry run shows it unneeded, as :mod:`.errands` reads it: no call fails that did
not, every stated goal that held still holds, every thing the instruction names or a goal is about ends as it did.
A knife the slice needs stays (the slice fails without it); the drop goes. Only the model's plan, its stated goals,
the instruction and the team are read; a plan with no stated goals is left as it is.
"""

from __future__ import annotations

import re
from collections.abc import Collection, Iterator, Sequence
from itertools import combinations

from ..executor.team_actions import RELEASE_ACTIONS
from ..robots import Robot
from ..scene import MASS_TOLERANCE, SceneObjects
from ..scoring import Condition
from ..skills import SkillSet
from ..world.object_types import base_type
from .constraints.feasibility import EXACT_COALITIONS, Need, can_do
from .errands import Unneeded
from .idle_steps import THREAD, Step, acts, comments_above, function_name, gotos_before, skill_steps

#: A top-level line of a decomposition's orchestration that starts or joins a thread, or calls a function.
_START = re.compile(r"^(\w+)\.(start|join)\(\)$")
_CALL = re.compile(r"^(\w+)\(\)$")


def free_blocks(text: str, scene: SceneObjects, skills: SkillSet, team: Sequence[Robot], instruction: str,
                goals: Sequence[Condition]) -> tuple[str, list[str]]:
    """The decomposition without the steps that alone kept a block of sub-tasks from having teams apart (and the
    GoToObject steps and comments that served them), and the lines taken out (none: the text as it was)."""
    lines = text.splitlines(keepends=True)
    steps = skill_steps(lines, skills) if goals else None
    if not steps or not 2 <= len(team) <= EXACT_COALITIONS:
        return text, []
    actions = {name: s.action for name, s in skills.items()}
    unneeded = Unneeded(steps, scene, skills, instruction, goals)
    dropped: set[int] = set()
    for block in blocks(lines):
        if apart(block, steps, dropped, actions, team, scene):
            continue
        for step in steps:
            if step.function not in block or not actions[step.skill] or base_type(step.objects[0]) in unneeded.asked \
                    or step.line in dropped:
                continue
            taken = dropped | {step.line} | gotos_before(steps, {step.line}, actions)
            if not acts(steps, step.function, taken, actions) or not apart(block, steps, taken, actions, team, scene):
                continue
            if unneeded(taken):
                dropped = taken
                break
    if not dropped:
        return text, []
    dropped |= comments_above(lines, dropped)
    return "".join(line for n, line in enumerate(lines) if n not in dropped), [lines[n] for n in sorted(dropped)]


def all_apart(lines: Sequence[str], skills: SkillSet, team: Sequence[Robot], scene: SceneObjects) -> bool:
    """Whether every block of sub-tasks the text starts at once has teams apart (a text of other lines: no)."""
    steps = skill_steps(lines, skills)
    if steps is None:
        return False
    actions = {name: s.action for name, s in skills.items()}
    return all(apart(block, steps, (), actions, team, scene) for block in blocks(lines))


def started_together(decomposition: str, calls_too: bool = True) -> list[set[int]]:
    """The functions (by order written) the coalition keeps teams apart for: each block of threads, and with
    ``calls_too`` each run of direct calls in a row."""
    lines = decomposition.splitlines(keepends=True)
    return [*blocks(lines), *(calls_in_a_row(lines) if calls_too else ())]


def blocks(lines: Sequence[str]) -> Iterator[set[int]]:
    """The functions (by order written) each block of the orchestration starts at once, where there are two or
    more: the threads started before a join."""
    order = _function_order(lines)
    targets: dict[str, str] = {}
    started: set[int] = set()
    for line in lines:
        line = line.rstrip("\n")
        if (made := THREAD.match(line)) is not None:
            targets[made.group(1)] = made.group(2)
        elif (went := _START.match(line)) is not None and went.group(1) in targets:
            if went.group(2) == "start" and targets[went.group(1)] in order:
                started.add(order[targets[went.group(1)]])
            elif went.group(2) == "join" and started:
                if len(started) > 1:
                    yield started
                started = set()
        elif _CALL.match(line) is not None and started:
            started = set()  # a direct call waits for nothing it does not follow


def calls_in_a_row(lines: Sequence[str]) -> Iterator[set[int]]:
    """The functions (by order written) of each run of two or more direct calls in a row: the allocation starts
    them at once where their teams are apart (``together``), so the coalition keeps their teams apart where it can.
    The 1.5B called its plunger's sub-task, then the one of the soap bottle and the light, and gave the plunger
    robots 28 and 8; the other waited for robot 8 (RU 0; dev9-c6): robot 28, helped by robot 24, lifts the plunger
    while robot 8 carries the soap bottle and switches the light off."""
    order = _function_order(lines)
    run: set[int] = set()
    for line in lines:
        if line.startswith((" ", "\t", "#", "def ")) or not line.strip():
            continue
        called = _CALL.match(line.rstrip("\n"))
        if called is not None and called.group(1) in order:
            run.add(order[called.group(1)])
            continue
        if len(run) > 1:
            yield run
        run = set()
    if len(run) > 1:
        yield run


def _function_order(lines: Sequence[str]) -> dict[str, int]:
    """Each function the text defines, by name, with its place in the order written."""
    return {function_name(line): k for k, line in enumerate(line for line in lines if line.startswith("def "))}


def apart(block: Collection[int], steps: Sequence[Step], dropped: Collection[int], actions: dict[str, str],
          team: Sequence[Robot], scene: SceneObjects) -> bool:
    """Whether each function of the block, its ``dropped`` steps left out, has a team of its own, no robot in two."""
    options = [_teams([s for s in steps if s.function == f and s.line not in dropped], actions, team, scene)
               for f in sorted(block)]

    def assign(k: int, used: frozenset[int]) -> bool:
        return k == len(options) or any(not used & t and assign(k + 1, used | t) for t in options[k])

    return assign(0, frozenset())


def _teams(steps: Sequence[Step], actions: dict[str, str], team: Sequence[Robot],
           scene: SceneObjects) -> list[frozenset[int]]:
    """The sets of the team's robots (by index) that can do the function's steps: what the coalition asks of a team
    (:func:`.constraints.feasibility.can_do`: every skill, the heaviest thing lifted, where its calls go), and for
    each thing picked up, one member that does all that is done to it while held."""
    heaviest = max((scene.masses.get(s.objects[0], 0.0) for s in steps if actions[s.skill] == "PickupObject"),
                   default=0.0)
    demands = (scene.world.call_demand(s.skill, s.objects) for s in steps)
    need = Need(frozenset(s.skill for s in steps), heaviest, frozenset(d for d in demands if d is not None))
    held: dict[str, set[str]] = {}
    for s in steps:
        if actions[s.skill] == "PickupObject":
            held.setdefault(s.objects[0], set()).add(s.skill)
        elif actions[s.skill] in RELEASE_ACTIONS and s.objects[0] in held:
            held[s.objects[0]].add(s.skill)
    able = []
    for n in range(1, len(team) + 1):
        for members in combinations(range(len(team)), n):
            robots = [team[i] for i in members]
            if can_do(robots, need) and all(_held_by_one(o, done, robots, scene, actions) for o, done in held.items()):
                able.append(frozenset(members))
    return able


def _held_by_one(thing: str, done: set[str], robots: Sequence[Robot], scene: SceneObjects,
                 actions: dict[str, str]) -> bool:
    """Whether one of the robots that pick it up lifts the thing alone and does all that is ``done`` to it while
    held; or none lifts it alone, so they lift (and put) it together. A member that cannot pick it up lifts
    nothing alone, however strong: it helps lift (``robots.team_lift``), so robot 24, that only switches, and robot
    8, too weak alone, carry a 1 kg statue together."""
    mass = scene.masses.get(thing, 0.0)
    picks = {s for s in done if actions[s] == "PickupObject"}
    lifts = [r for r in robots if r.mass_capacity + MASS_TOLERANCE >= mass and picks & r.skills]
    return not lifts or any(done <= r.skills for r in lifts)
