"""An opening one sub-task makes for another started beside it, moved into the sub-task that needs it.

Asked to put the plunger and the cloth from the cabinet on the counter, the 1.5B's first sub-task carried the plunger,
then went to the cloth and opened its cabinet; the second, started at once, took the cloth out. Run at once, the
second would find the cabinet shut, so the allocation ran it after the first: a transition the reference plan, where
the robot that takes the cloth opens the cabinet itself, does not make (RU 0 for a plan that met every goal; dev8-c5).

So where a sub-task's last action is an OpenObject, and another sub-task of its block (started at once, written after
it) then takes a thing out of that holder or puts one in it (in the dry run: a notional robot per sub-task, in the
order written), the opening moves to just before that other sub-task's first step on the holder or on a thing in it
(and the comments that say that step), and the GoToObject steps right before it where it was, with the comments
above them, go, where the text so made fails no more calls and leaves the world alike as the goals see it. An
opening its own sub-task goes on to use stays.
"""

from __future__ import annotations

from collections.abc import Sequence

from ..scene import SceneObjects
from ..skills import SkillSet
from .constraints.format import MAX_SUBTASKS
from .constraints.world_check import WorldCheck
from .idle_steps import Step, acts, comments_above, ends_as, gotos_before, outcomes, skill_steps, text_outcome
from .in_turn import blocks

#: How many openings one decomposition may have moved (each move is checked in a dry run of its own).
MAX_MOVES = 4


def move_openings(text: str, scene: SceneObjects, skills: SkillSet) -> tuple[str, list[str]]:
    """The decomposition with each opening made for another sub-task of its block moved into that one, and the
    opening lines moved (none: the text as it was)."""
    moved: list[str] = []
    for _ in range(MAX_MOVES):
        lines = text.splitlines(keepends=True)
        trial = _one_move(lines, scene, skills)
        if trial is None:
            break
        text, line = trial
        moved.append(line)
    return text, moved


def _one_move(lines: list[str], scene: SceneObjects, skills: SkillSet) -> tuple[str, str] | None:
    """The text with the first opening that can move moved, and its line; None where none can."""
    steps = skill_steps(lines, skills)
    if not steps:
        return None
    actions = {name: s.action for name, s in skills.items()}
    base = None
    for opening, target in _candidates(steps, lines, scene, skills, actions):
        taken = {opening.line} | gotos_before(steps, {opening.line}, actions)
        if not acts(steps, opening.function, taken, actions):
            continue  # the sub-task would be left with nothing to do
        taken |= comments_above(lines, taken)
        at = min({target.line} | comments_above(lines, {target.line}))  # before the comments that say the step
        after = [line for n, line in enumerate(lines[:at]) if n not in taken]
        after += [lines[opening.line]] + [line for n, line in enumerate(lines) if n >= at and n not in taken]
        base = base or text_outcome(lines, scene, skills)
        if ends_as(base, after, scene, skills):
            return "".join(after), lines[opening.line]
    return None


def _candidates(steps: Sequence[Step], lines: Sequence[str], scene: SceneObjects, skills: SkillSet,
                actions: dict[str, str]) -> list[tuple[Step, Step]]:
    """Each opening that is its sub-task's last action, with the first step of a later sub-task of its block on the
    holder or a thing it held once opened."""
    started = {f: block for block in blocks(lines) for f in block}
    world = WorldCheck(scene, skills, MAX_SUBTASKS)
    opened: list[tuple[Step, str, set[str]]] = []
    found: dict[int, tuple[Step, Step]] = {}  # an opening's line -> it and the first step it serves
    for step, outcome in outcomes(world, steps):
        if not outcome.success or not actions[step.skill]:
            continue
        if actions[step.skill] == "OpenObject" and outcome.object_id and step.function in started and not any(
                actions[s.skill] for s in steps if s.function == step.function and s.line > step.line):
            holder = next(o for o in world.run.objects if o["objectId"] == outcome.object_id)
            inside = {o["objectType"] for o in world.run.objects
                      if o["objectId"] in (holder.get("receptacleObjectIds") or ())}
            opened.append((step, holder["objectType"], inside))
            continue
        for opening, holder, inside in opened:
            if opening.line not in found and step.function > opening.function \
                    and step.function in started[opening.function] \
                    and (step.objects[0] in inside or holder in step.objects[1:]):
                found[opening.line] = (opening, step)
    return list(found.values())
