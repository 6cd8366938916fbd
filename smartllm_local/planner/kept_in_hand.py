"""Things a sub-task's robot keeps in hand, put where a stated goal wants them, by that sub-task.

A small model picks a thing up and ends its sub-task with it in hand: asked to put the candle and the soap bar on
the counter, the 0.5B carried the candle about, set it on the floor, picked it up again and ended there. The
planner's last sub-task (:mod:`.constraints.finish`) cannot help: its robot is another, and a thing in a robot's
hand is out of every other robot's reach; the counter got the soap bar alone. The robot holding the thing can:
where a stated goal puts a thing in a holder and the thing ends the dry run (a notional robot per sub-task, in the
order written, as the world check runs a decomposition) in the hand of a sub-task's robot, Fast Downward's
shortest plan for that robot, from that end, to put it there with empty hands (the repair's,
:mod:`.constraints.repair`) is written at the end of that sub-task, after a comment naming the goal, where the dry
run then fails no more calls and meets more stated goals. Only the decomposition's text and its stated goals are
read.
"""

from __future__ import annotations

from collections.abc import Sequence

from ..goal_language import condition_line
from ..scene import SceneObjects
from ..scoring import Condition
from ..skills import SkillSet
from ..world.object_types import base_type
from .constraints.candidates import call_line
from .constraints.format import INDENT, MAX_SUBTASKS
from .constraints.repair import Repairer
from .constraints.world_check import WorldCheck
from .idle_steps import body_end, dry_run, skill_steps

#: The most steps the robot's plan may take (going to a holder, opening it, putting the thing in: a few).
MOST_STEPS = 6


def put_kept_things(text: str, scene: SceneObjects, skills: SkillSet,
                    goals: Sequence[Condition]) -> tuple[str, list[str]]:
    """The decomposition with the steps that put each thing a sub-task's robot ends holding where a stated goal
    wants it written at the end of that sub-task, and the lines written (none: the text as it was)."""
    lines = text.splitlines(keepends=True)
    placements = [c for c in goals if c.item]
    steps = skill_steps(lines, skills) if placements else None
    if not steps:
        return text, []
    failed, world = dry_run(steps, (), scene, skills)
    if not Repairer.fits(world):
        return text, []
    added: list[str] = []
    while (found := _put_away(lines, world, skills, placements)) is not None:
        header, written = found
        end = body_end(lines, header)
        trial = lines[:end] + written + lines[end:]
        trial_steps = skill_steps(trial, skills)
        if trial_steps is None:
            break
        trial_failed, trial_world = dry_run(trial_steps, (), scene, skills)
        if len(trial_failed) > len(failed) or trial_world.met(goals) <= world.met(goals):
            break
        lines, added, failed, world = trial, added + written, trial_failed, trial_world
    return "".join(lines), added


def _put_away(lines: Sequence[str], world: WorldCheck, skills: SkillSet,
              placements: Sequence[Condition]) -> tuple[int, list[str]] | None:
    """The first sub-task whose robot ends holding a thing a goal of ``placements`` (unmet) puts somewhere, and the
    lines (a comment, then the calls) that put it there; None where there is none or no plan does it."""
    defs = [n for n, line in enumerate(lines) if line.startswith("def ")][:MAX_SUBTASKS]
    repairer = Repairer(world, skills)
    for member, header in enumerate(defs):
        held = world.run.world.holding(member)
        if held is None:
            continue
        kind = base_type(held["objectType"])
        for goal in placements:
            if base_type(goal.item or "") != kind or world.met([goal]):
                continue
            plan = repairer.meet(member, [goal], MOST_STEPS)
            if plan is not None:
                calls = [call_line(skill, objects) for skill, objects in plan.calls]
                return header, [f"{INDENT}# then put it where it goes: {condition_line(goal)}\n", *calls]
    return None
