"""Errands nobody asked for, taken out of a decomposition before the teams are formed.

A small model carries things nobody asked it to: asked for a coffee and the apple in the fridge, the 1.5B switched
the coffee machine on and then took a cup to the fridge. The cup is in no goal, but the coalition takes every step
as a need: the coffee's sub-task then needs a robot that opens fridges as well as one that switches machines on,
and the apple's sub-task waits for it (a transition the reference plan does not make: RU 0 for a plan that met
every goal).

So a thing a sub-task picks up that the instruction does not name and no stated goal is about is an errand: the
sub-task's steps on it (going to it, picking it up, putting or dropping it), with the GoToObject steps that led to
each and the comments right above them, are taken out where the dry run (a notional robot per sub-task, in the
order written) shows them unneeded: no call fails that did not, every stated goal that held still holds, and the
sub-task keeps an action. A knife fetched for a slice stays (the slice fails without it), as does anything the
instruction names. An open and close left with nothing put in between is then taken out by :mod:`.idle_steps`.
Only the model's own plan, its stated goals and the instruction are read; a plan with no stated goals is left as
it is.
"""

from __future__ import annotations

from collections.abc import Sequence

from ..scene import SceneObjects
from ..scoring import Condition
from ..skills import SkillSet
from ..world.object_types import base_type
from .asked import names
from .idle_steps import Step, acts, comments_above, dry_run, gotos_before, skill_steps


def drop_errands(text: str, scene: SceneObjects, skills: SkillSet, instruction: str,
                 goals: Sequence[Condition]) -> tuple[str, list[str]]:
    """The decomposition without its errands (and the GoToObject steps and comments that served them), and the
    lines taken out (none: the text as it was)."""
    lines = text.splitlines(keepends=True)
    steps = skill_steps(lines, skills) if goals else None
    if not steps:
        return text, []
    actions = {name: s.action for name, s in skills.items()}
    wanted = {base_type(o) for c in goals for o in (c.subject, c.item) if o}
    base_failed, world = dry_run(steps, set(), scene, skills)
    base_met = world.met(goals)
    dropped: set[int] = set()
    for function, thing in _carried(steps, actions):
        if thing in wanted or names(instruction, thing):
            continue
        errand = {s.line for s in steps if s.function == function and s.objects and base_type(s.objects[0]) == thing}
        taken = dropped | errand | gotos_before(steps, errand, actions)
        if not acts(steps, function, taken, actions):
            continue
        failed, world = dry_run(steps, taken, scene, skills)
        if failed <= base_failed and world.met(goals) >= base_met:
            dropped = taken
    if not dropped:
        return text, []
    dropped |= comments_above(lines, dropped)
    return "".join(line for n, line in enumerate(lines) if n not in dropped), [lines[n] for n in sorted(dropped)]


def _carried(steps: Sequence[Step], actions: dict[str, str]) -> list[tuple[int, str]]:
    """Each function's picked-up object types, in the order first picked up."""
    seen: list[tuple[int, str]] = []
    for step in steps:
        key = (step.function, base_type(step.objects[0]))
        if actions[step.skill] == "PickupObject" and key not in seen:
            seen.append(key)
    return seen
