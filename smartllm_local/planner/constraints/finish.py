"""The planner's last sub-task: the stated goals the model's sub-tasks left unmet, met by Fast Downward.

With the goal stage run first and a world check, once the model has written its sub-tasks and launched them, the
stated goals that do not hold in the dry run and that the plan left open go to the planner (the repair's,
:mod:`.repair`): a thing's place where none of its calls put the thing anywhere, a state where none acted on it
(goals it forgot: the newspaper pushed, never thrown out; the credit card for the box let fall on the desk; where it
put the thing somewhere, or acted on the one whose state is stated, the plan has its own idea of it, and a statement
that contradicts the plan is as likely wrong as the plan), and every goal the instruction asks for in so many words,
whatever the plan did (:class:`Said`: the words outrank both; asked to put three things on the bed, the 0.5B put the
basketball on the floor it was asked to pick it up off, and ended).
For a robot no sub-task has used, its shortest plan that meets them all and ends with empty hands is written as one
more sub-task, called after the model's orchestration, so it starts from the state the model's sub-tasks leave (the
state it was planned from), every step succeeding in the dry run. Where no plan meets them all in twice the steps
of a sub-task of the model's (:data:`LONGER`) and in the budget (a wrong goal stated beside a right one:
"CounterTop empty" beside "Plunger in GarbageCan" for "throw the old plunger out"), the most of those whose thing
the instruction names are met (each alone first, then the largest sets of those met alone, in the order stated), for
at most :data:`MOST_SUBSETS` goals left (beyond that, all or nothing: each set is a search). A goal on a thing nobody
named ("TennisRacket in Bed" for "the bed is a mess") is met only with every other goal left: a statement wrong
enough to hold a goal no plan meets holds others as wrong.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from itertools import combinations
from typing import Any

from ...goal_language import condition_line
from ...scoring import Condition
from ...skills import Skill
from ...world.object_types import base_type
from .candidates import Candidates
from .feasibility import WholeTeam
from .format import INDENT
from .repair import Repair, Repairer
from .world_check import WorldCheck, held

#: The name of the planner's sub-task (after ``subtask<k>_``).
NAME = "meet_goals"
#: The most goals left for which smaller sets are sought when no plan meets them all.
MOST_SUBSETS = 4
#: How many times a model's sub-task's steps the planner's may take: its steps are Fast Downward's shortest plan,
#: checked in the dry run as written, not a model's that may wander (frying the potato and putting the bread in
#: the fridge, both left to it, take 14 steps).
LONGER = 2
#: The room (in characters) the model's sub-tasks leave for the planner's last one, where the budget has it to spare:
#: a sub-task of about six steps. Lines the planner took out of the model's text cost tokens all the same, and the
#: 0.5B's seven sub-tasks of wandering once left too little for the CD its plan had not put on the bed (dev4-c3).
ROOM = 256


@dataclass(frozen=True)
class Said:
    """What the instruction says of the stated goals, as the planner's last sub-task reads it: ``asked``, the goals
    whose thing it names; ``owed``, those it asks for in so many words (a state, a thing put where it names), which no
    plan's idea overrules; ``holders``, the holders it names (not by a word of another thing's name: the desk lamp's
    desk is no desk), each with the things its words put there (none: any thing)."""

    asked: tuple[Condition, ...] = ()
    owed: tuple[Condition, ...] = ()
    holders: Mapping[str, tuple[str, ...]] = field(default_factory=dict)

    def meant_for(self, thing: str) -> set[str]:
        """The holders named that the words may mean ``thing`` to go in: not one they put other things in only
        ("put the apple in the fridge" names the fridge for the apple, not for the mug)."""
        return {holder for holder, things in self.holders.items() if not things or thing in things}


class Finish:
    """One decomposition's last sub-task, sought once its model has ended (``made``: what was written)."""

    def __init__(self, repairer: Repairer, candidates: Candidates, whole: WholeTeam | None,
                 goals: Sequence[Condition], max_steps: int, skills: dict[str, Skill], said: Said = Said()):
        self.repairer, self.candidates, self.whole, self.goals, self.max_steps, self.skills = \
            repairer, candidates, whole, list(goals), max_steps * LONGER, skills
        self.said = said
        self.made: dict[str, Any] | None = None

    def text(self, world: WorldCheck, k: int, room: int, acted: set[str], put: set[str],
             cost: Callable[[str], int] = len) -> str | None:
        """Sub-task ``k`` (its definition and its call) within ``room`` tokens (``cost``), or None: no goal left
        unmet that the instruction owes or the plan left open (a thing's place where none of the types ``put``
        somewhere was it, or where it was put only in holders the instruction does not name for it while the
        goal's holder is named; a state where none ``acted`` on was it), no robot left for it, or no plan that
        meets any."""
        holding = [c for c in self.goals if world.met([c])]
        left = [c for c in self.goals if c not in holding and (
            c in self.said.owed or (self._left_open(world, c, put) if c.item else base_type(c.subject) not in acted))]
        if not left or k > len(world.run.team):
            return None
        met = self._meet(k - 1, left, holding)
        if met is None:
            return None
        unmet, found = met
        name = f"subtask{k}_{NAME}"
        said = [condition_line(c) for c in unmet]
        lines = [self.candidates.line((self.skills[skill], objects)) for skill, objects in found.calls]
        text = f"def {name}():\n{INDENT}# the goals left: {'; '.join(said)}\n{''.join(lines)}\n{name}()\n"
        if cost(text) > room:
            return None
        self.made = {"goals": said, "lines": lines, "seconds": found.seconds}
        return text

    def _left_open(self, world: WorldCheck, goal: Condition, put: set[str]) -> bool:
        """Whether the plan left a thing's place open: it never put the thing anywhere (it let it fall, or never
        carried it), or it put it only where the instruction names no holder for it (the book for the desk put on
        the floor; the mug for the coffee machine in the fridge named for the apple) while it names the goal's."""
        thing = base_type(goal.item or "")
        if thing not in put:
            return True
        holders = {holder for kind, holder in held(world.objects()) if kind == thing}
        return goal.subject in self.said.holders and not holders & self.said.meant_for(thing)

    def _meet(self, member: int, left: Sequence[Condition],
              holding: Sequence[Condition]) -> tuple[list[Condition], Repair] | None:
        """The most goals of ``left`` one plan meets, and that plan: all of them, keeping the goals ``holding`` if
        it can (the drawer closed again once the laptop is in it); failing that (for a few), of those whose thing
        the instruction names, each alone, then the largest sets of those met alone, in the order stated."""
        whole = self.whole

        def meet(goals: Sequence[Condition]) -> Repair | None:
            return self.repairer.meet(member, goals, self.max_steps, allows=whole.can if whole else None,
                                      skills=whole.skills if whole else None)

        every = (meet([*left, *holding]) if holding else None) or meet(left)
        if every is not None:
            return list(left), every
        if len(left) > MOST_SUBSETS:
            return None
        alone = {n: plan for n, c in enumerate(left) if c in self.said.asked and (plan := meet([c])) is not None}
        for size in range(len(alone) - (len(alone) == len(left)), 1, -1):
            for chosen in combinations(sorted(alone), size):
                if (plan := meet([left[n] for n in chosen])) is not None:
                    return [left[n] for n in chosen], plan
        return next(([left[n]], plan) for n, plan in alone.items()) if alone else None
