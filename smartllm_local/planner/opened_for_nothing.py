"""Holders opened for nothing, their opening taken out of a decomposition before the teams are formed.

Asked to put the plunger and the towel in the cabinet, the 1.5B opened a cabinet in its first sub-task and then put
a candle and a cloth in it (errands nobody asked for, taken out by :mod:`.errands`); the planner's last sub-task
opened another cabinet and put both things in that. The first sub-task was left opening a cabinet nothing went
into: harmless to the goals, but a sub-task all the same, so the planner's ran after it, a transition the reference
plan does not make (RU 0 for a plan that met every goal; dev6-c6). The errands' rule keeps such an opening, since
the cabinet, a thing the instruction names, would end shut without it.

So an OpenObject step whose holder ends open with the same things in it as when it was opened (in the dry run: a
notional robot per sub-task, in the order written) is taken out, with the GoToObject step right before it and the
comments above (a sub-task left with no action, whole, where another still acts), where without it no call fails
and every stated goal met still is. Not where a call fails with it: once the errands took the 1.5B's first
sub-task out whole, the planner's last one ran for another notional robot, opened a cabinet beside the spray
bottle's and failed to pick the bottle up; that opening looked unused, and without it the allocation found no robot
list for the bottle (bathroom-05). Not where a stated goal is about the holder's type being open or
shut, or the instruction's words ask something opened or shut ("open the blinds": the goal stage may leave the
state out, the words do not), nor in a plan with no stated goals.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from ..scene import SceneObjects
from ..scoring import Condition
from ..skills import SkillSet
from .constraints.format import MAX_SUBTASKS
from .constraints.world_check import WorldCheck
from .idle_steps import Step, acts, comments_above, dry_run, function_lines, gotos_before, outcomes, skill_steps
from .prompting.asked_words import load_state_words, states_asked

#: The states that say a holder is to be open or shut.
_OPENNESS = frozenset({"OPENED", "CLOSED"})


def drop_opened_for_nothing(text: str, scene: SceneObjects, skills: SkillSet, instruction: str,
                            goals: Sequence[Condition]) -> tuple[str, list[str]]:
    """The decomposition without the openings of holders nothing went in or came out of (and the GoToObject steps
    and comments that served them; a sub-task left with no action, whole), and the lines taken out (none: the
    text as it was)."""
    lines = text.splitlines(keepends=True)
    steps = skill_steps(lines, skills) if goals and not _openness_asked(instruction, scene, goals) else None
    if not steps:
        return text, []
    actions = {name: s.action for name, s in skills.items()}
    unused, failed, world = _unused_openings(steps, scene, skills, actions)
    if not unused or failed:  # a dry run that fails already is no picture of the plan (a sub-task gone shifts
        return text, []       # the robots)
    met = [c for c in goals if world.met([c])]
    dropped: set[int] = set()
    gone: set[int] = set()
    for step in unused:
        taken = dropped | {step.line} | gotos_before(steps, {step.line}, actions)
        emptied = set() if acts(steps, step.function, taken, actions) else {step.function}
        if emptied and not any(acts(steps, s.function, taken, actions) for s in steps):
            continue  # the plan keeps a sub-task
        taken |= {s.line for s in steps if s.function in emptied}
        now_failed, now = dry_run(steps, taken, scene, skills)
        if now_failed <= failed and now.met(met) == len(met):
            dropped, gone = taken, gone | emptied
    if not dropped:
        return text, []
    dropped |= comments_above(lines, dropped)
    for function in gone:
        dropped |= function_lines(lines, function)
    return "".join(line for n, line in enumerate(lines) if n not in dropped), [lines[n] for n in sorted(dropped)]


def _openness_asked(instruction: str, scene: SceneObjects, goals: Sequence[Condition]) -> bool:
    """Whether a stated goal or the instruction's words want something open or shut."""
    if any(c.state in _OPENNESS for c in goals):
        return True
    words = load_state_words(scene.world.examples_dir())
    return bool(_OPENNESS & set(states_asked(instruction, words.asked, words.verbs)))


def _unused_openings(steps: Sequence[Step], scene: SceneObjects, skills: SkillSet,
                     actions: dict[str, str]) -> tuple[list[Step], set[int], WorldCheck]:
    """The OpenObject steps whose holder ends open holding what it held once opened, the lines whose calls fail and
    the world left, in one dry run (:func:`.idle_steps.dry_run`'s)."""
    world = WorldCheck(scene, skills, MAX_SUBTASKS)
    opened: list[tuple[Step, str, tuple[bool, list[str]]]] = []
    failed: set[int] = set()
    for step, outcome in outcomes(world, steps):
        if not outcome.success:
            failed.add(step.line)
        elif actions[step.skill] == "OpenObject" and outcome.object_id:
            opened.append((step, outcome.object_id, _open_holding(world.run.objects, outcome.object_id)))
    unused = [step for step, holder, once_opened in opened if _open_holding(world.run.objects, holder) == once_opened]
    return unused, failed, world


def _open_holding(objects: Sequence[Mapping[str, Any]], holder: str) -> tuple[bool, list[str]]:
    """Whether ``holder`` is open, and what it holds (sorted): the same read once opened and at the end."""
    obj = next(o for o in objects if o["objectId"] == holder)
    return bool(obj.get("isOpen")), sorted(obj.get("receptacleObjectIds") or [])
