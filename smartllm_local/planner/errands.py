"""Errands nobody asked for, taken out of a decomposition before the teams are formed.

A small model carries things nobody asked it to: asked for a coffee and the apple in the fridge, the 1.5B switched
the coffee machine on and then took a cup to the fridge. The cup is in no goal, but the coalition takes every step
as a need: the coffee's sub-task then needs a robot that opens fridges as well as one that switches machines on,
and the apple's sub-task waits for it (a transition the reference plan does not make: RU 0 for a plan that met
every goal).

So a sub-task's steps on a thing it acts on (picks up, switches, opens, pulls...), with the GoToObject steps that
led to each, the sleeps after a switch-on and the comments right above them, are an errand where the dry run (a
notional robot per sub-task, in the order written) shows them unneeded: no call fails that did not, every stated
goal that held still holds, every thing the instruction names or a goal is about ends as it did (what it holds
aside: a cup nobody asked for leaves the fridge; its pieces only where a goal is about them or the thing itself, not
where it only wants it cut: :func:`asked_types`). A thing is named by words that are not part of another thing's
name ("get the spray bottle" names no SoapBottle: the 1.5B carried the soap bottle beside it to the counter, and
the sub-task that did held a robot). On a thing nobody named that is a thing nobody asked for; on a
named one, steps that change nothing of how it ends (the cloth pushed in the bathtub before another sub-task
carries it to the counter: the push needed a robot that pushes, and the carrying sub-task waited for it); where the
GoToObject steps that led to them lead on to a step on another thing too, the steps alone (the cloth pushed after its
cabinet was opened from beside it: dev8-c5). A
sub-task whose every action is an errand goes whole (its definition, and its thread or its call) where another
sub-task still acts. A knife fetched for a slice stays (the slice fails without it), as does a faucet that fills a
mug the instruction names (the mug would end empty). The fridge opened and closed for the cup alone ends as it was
without those steps, so they go in the same pass; a pair of steps that undo each other beside others on the same
thing, or in a plan with no stated goals, is :mod:`.idle_steps`' to take out. Only the model's own plan, its stated
goals and the instruction are read; a plan with no stated goals is left as it is.
"""

from __future__ import annotations

import json
from collections.abc import Collection, Sequence

from ..scene import SceneObjects
from ..scoring import Condition
from ..skills import SkillSet
from ..world.object_types import SLICE_RESULTS, base_type
from .asked import named_apart
from .constraints.world_check import WorldCheck
from .idle_steps import (
    WHERE_ROBOTS_STAND,
    Step,
    acts,
    comments_above,
    dry_run,
    function_lines,
    gotos_before,
    skill_steps,
    sleeps_after,
)

#: An object's fields that an errand may change on a thing that was asked for: where the robots stand, and what it
#: holds (each thing held is an object of its own, asked for or not).
_ASIDE = WHERE_ROBOTS_STAND | {"receptacleObjectIds"}
#: A held thing's fields that say where the robot holding it stands (it is in a hand either way).
_CARRIED = frozenset({"position", "rotation", "axisAlignedBoundingBox", "objectOrientedBoundingBox"})


def drop_errands(text: str, scene: SceneObjects, skills: SkillSet, instruction: str,
                 goals: Sequence[Condition]) -> tuple[str, list[str]]:
    """The decomposition without its errands (and the GoToObject steps and comments that served them; a sub-task of
    errands alone, whole), and the lines taken out (none: the text as it was)."""
    lines = text.splitlines(keepends=True)
    steps = skill_steps(lines, skills) if goals else None
    if not steps:
        return text, []
    actions = {name: s.action for name, s in skills.items()}
    unneeded = Unneeded(steps, scene, skills, instruction, goals)
    dropped: set[int] = set()
    gone: set[int] = set()  # functions all of whose actions were errands
    for function, thing in _handled(steps, actions):
        errand = {s.line for s in steps if s.function == function and s.objects and base_type(s.objects[0]) == thing}
        taken = dropped | errand | gotos_before(steps, errand, actions)
        whole = not acts(steps, function, taken, actions)
        if whole:
            if not any(acts(steps, s.function, taken, actions) for s in steps if s.function != function):
                continue  # the plan keeps a sub-task
            taken |= {s.line for s in steps if s.function == function}
        if unneeded(taken):
            dropped = taken
            gone |= {function} if whole else set()
        elif not whole and (acting := {s.line for s in steps if s.line in errand and actions[s.skill]}) \
                and unneeded(dropped | acting):  # a go-to to the thing may lead to the next step too
            dropped |= acting
    if not dropped:
        return text, []
    dropped |= sleeps_after(lines, steps, dropped, actions)
    dropped |= comments_above(lines, dropped)
    for function in gone:
        dropped |= function_lines(lines, function)
    return "".join(line for n, line in enumerate(lines) if n not in dropped), [lines[n] for n in sorted(dropped)]


class Unneeded:
    """Whether steps of a decomposition can go, by the dry run (a notional robot per sub-task, in the order
    written): without them no call fails that did not, every stated goal that held still holds, and every thing of
    the types ``asked`` (a stated goal is about them, or the instruction names them) ends as it did."""

    def __init__(self, steps: Sequence[Step], scene: SceneObjects, skills: SkillSet, instruction: str,
                 goals: Sequence[Condition]):
        self.steps, self.scene, self.skills, self.goals = steps, scene, skills, goals
        self.asked = asked_types(scene, instruction, goals)
        self.failed, world = dry_run(steps, set(), scene, skills)
        self.met, self.ends = world.met(goals), _ends(world, self.asked)

    def __call__(self, taken: Collection[int]) -> bool:
        """Whether the steps on the lines ``taken`` can go."""
        failed, world = dry_run(self.steps, taken, self.scene, self.skills)
        return failed <= self.failed and world.met(self.goals) >= self.met and _ends(world, self.asked) == self.ends


def asked_types(scene: SceneObjects, instruction: str, goals: Sequence[Condition]) -> set[str]:
    """The types whose things must end as they did: those a stated goal is about and those the instruction names,
    with their pieces where a goal is about the thing itself (the scorer counts a slice of the apple put in the
    fridge as the apple), not where it only wants it cut: asked to open the fridge and cut the apple, the 0.5B carried
    a slice to the fridge, and the sub-task that did waited for the cutting."""
    about = {o for c in goals for o in (c.subject, c.item) if o}
    whole = {base_type(o) for c in goals for o in (c.subject, c.item) if o and not (o == c.subject and c.state
                                                                                    == "SLICED")}
    named = {base_type(t) for t in scene.types if named_apart(instruction, t, scene.types)}
    return about | named | {base_type(o) for o in about} | {SLICE_RESULTS[t][0] for t in whole if t in SLICE_RESULTS}


def _handled(steps: Sequence[Step], actions: dict[str, str]) -> list[tuple[int, str]]:
    """Each function's object types that a step acts on (picks up, switches, opens, pulls...), in the order first
    acted on; a GoToObject alone acts on nothing."""
    seen: list[tuple[int, str]] = []
    for step in steps:
        key = (step.function, base_type(step.objects[0]))
        if actions[step.skill] and key not in seen:
            seen.append(key)
    return seen


def _ends(world: WorldCheck, asked: Collection[str]) -> str:
    """How the things of the asked types end, what they hold aside, and where a thing held is (by its robot):
    asked to open the fridge and cut the apple, the 0.5B carried a slice to the fridge and on to open the
    microwave; without the microwave's steps the slice ends in the same hand by the fridge."""
    return json.dumps([{k: v for k, v in o.items() if k not in _ASIDE and not (o.get("isPickedUp") and k in _CARRIED)}
                       for o in world.objects() if o["objectType"] in asked], sort_keys=True, default=str)
