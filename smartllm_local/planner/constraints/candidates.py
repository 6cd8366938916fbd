"""The skill calls a plan's function may write next, and how long their lines are.

A call is a candidate when the function's own steps do not rule it out (put down only what it holds,
slice only with a knife in hand, do not undo the step just taken); with a world check, only the
candidates that succeed from the state the steps so far produce are offered (see :mod:`.world_check`).
The plan constraint (:mod:`.plan`) keeps the budget on these lines' longest texts.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

from ...executor.team_actions import KNIVES, RELEASE_ACTIONS
from ...scene import SceneObjects
from ...scoring import Condition
from ...skills import Skill
from ...world.object_types import RECEPTACLE_ONLY_ACCEPTS, base_type
from ..decoding.grammar import Node, Ref, alt, seq
from .format import INDENT
from .world_check import WorldCheck

if TYPE_CHECKING:
    from .written import WrittenFunction

Candidate = tuple[Skill, tuple[str, ...]]
#: Whether a plan may make a call at all (a skill's name and its objects); see feasibility.WholeTeam.
Allows = Callable[[str, Sequence[str]], bool]
# Actions that set a state, and the action that undoes each.
STATE_ACTIONS = {"OpenObject": "CloseObject", "CloseObject": "OpenObject",
                 "ToggleObjectOn": "ToggleObjectOff", "ToggleObjectOff": "ToggleObjectOn"}
#: The states a thing may be broken or cut to reach: broken or sliced itself, and cooked (an egg cooks once cracked).
BROKEN_FOR = frozenset({"BROKEN", "SLICED", "COOKED"})
#: The actions that leave a thing in pieces.
CUTTING = frozenset({"BreakObject", "SliceObject"})


def wanted_whole(goals: Sequence[Condition]) -> frozenset[str]:
    """The types stated goals want whole, which no call may break or cut: a thing put somewhere and what holds it, a
    thing whose state is stated, save one a goal wants in pieces (a state of :data:`BROKEN_FOR`, a goal on its pieces:
    an egg is fried cracked, or a holder that takes only its pieces: bread in the toaster). Asked to slice the potato
    and put the wine bottle in the fridge, the 0.5B broke the bottle, and no plan could then put it anywhere; asked to
    cut the bread and put the apple in the microwave, it cut the apple too."""
    named = _goal_types(goals)
    in_pieces = {c.subject for c in goals if c.state in BROKEN_FOR} | {base_type(n) for n in named if base_type(n) != n}
    in_pieces |= {c.item for c in goals if c.item and any(base_type(t) == c.item != t
                                                           for t in RECEPTACLE_ONLY_ACCEPTS.get(c.subject, ()))}
    return frozenset(named - in_pieces)


def held_for_good(goals: Sequence[Condition], skills: Sequence[Skill]) -> frozenset[str] | None:
    """For a team that can never let a thing go (no skill of :data:`RELEASE_ACTIONS`), the only types a pick-up may
    take: a knife where the goals want a thing in pieces, and a thing a goal wants held; None for a team that can,
    or with no goals. Asked to chop the potato, the 0.5B had robot 26 (picks up and slices) pick up the potato, and
    it could then never hold a knife (dev11-e6)."""
    if not goals or lets_go(skills):
        return None
    cut = any(c.state == "SLICED" for c in goals) or any(base_type(n) != n for n in _goal_types(goals))
    return (KNIVES if cut else frozenset()) | {c.subject for c in goals if c.state == "PICKED"}


def lets_go(skills: Iterable[Skill]) -> bool:
    """Whether some skill lets a robot let go of what it holds (an action of :data:`RELEASE_ACTIONS`)."""
    return any(s.action in RELEASE_ACTIONS for s in skills)


def _goal_types(goals: Sequence[Condition]) -> set[str]:
    """The types the goals are about: what they put somewhere, what holds it, what is to be in a state."""
    return {n for c in goals for n in ((c.item, c.subject) if c.item else (c.subject,))}


def args_text(objects: Sequence[str]) -> str:
    return ", ".join(f"'{t}'" for t in objects)


def call_line(skill: str, objects: Sequence[str]) -> str:
    """A decomposition's line for a call of the skill named ``skill`` on ``objects``."""
    return f"{INDENT}{skill}({args_text(objects)})\n"


def acts_on(candidate: Candidate) -> str | None:
    """Where a call acts: its object, a put's receptacle; None for dropping or throwing what is held.
    With a world check a call acts only on what the function last went to, or a holder of it: where exactly a
    robot stands depends on where the others stand, and only the object gone to is surely within reach."""
    skill, objects = candidate
    if skill.action == "PutObject":
        return objects[1]
    return None if skill.action in ("DropHandObject", "ThrowObject") else objects[0]


class Candidates:
    """The action and GoToObject calls of a scene's skills, filtered by what a function has done."""

    def __init__(self, scene: SceneObjects, skills: Sequence[Skill], *, robot_arg_len: int, allocated: bool,
                 world: WorldCheck | None, max_steps: int, allows: Allows | None = None,
                 spared: frozenset[str] = frozenset(), kept: frozenset[str] | None = None):
        """``allows``: the calls a plan may make at all (the team's); none given, every call of ``skills``.
        ``spared``: the types no call breaks or cuts (:func:`wanted_whole`); ``kept``: the only types a call may
        pick up, where any (:func:`held_for_good`)."""
        self.scene = scene
        self.allows, self.spared, self.kept = allows, spared, kept
        self.skills = list(skills)
        self.gotos = [s for s in self.skills if s.action == ""]
        self.robot_arg_len = robot_arg_len
        self.allocated = allocated
        self.world = world
        self.max_steps = max_steps
        # Where the world says a move is an end in itself (a site's: back to base), a function may end with
        # one, or make two.
        self.goto_acts = scene.world.goto_acts
        self._cache: dict[tuple, list[Candidate]] = {}
        self._every = list(self._filtered(None))
        self.action_max = max(self.line_len(c) for c in self._every)
        releases = [c for c in self._filtered(None) if c[0].action == "DropHandObject"] or \
            [c for c in self._filtered(None) if c[0].action in RELEASE_ACTIONS]
        self.release_max = max((self.line_len(c) for c in releases), default=self.action_max)
        self.goto_max = max(self.line_len(c) for c in self.goto_calls())

    def fresh_action(self, fresh: WrittenFunction) -> int:
        """A new function's cheapest body: one action; with a world check, the cheapest GoToObject and
        an action where it went (what is picked up put down again), so that each sub-task promised
        keeps room for a go-to and an action there (the budget is kept all the same)."""
        if self.world is None:
            return min(self.line_len(c) for c in self.of(fresh))
        return min(
            self.line_len(goto) + min((self.line_len(c) + self.hold_after(fresh, c) for c in self.of(fresh)
                                       if acts_on(c) in (goto[1][0], None)), default=self.action_max * 2)
            for goto in self.goto_calls())

    def line_len(self, candidate: Candidate) -> int:
        """The longest text of a candidate's line (its longest robot argument included)."""
        skill, objects = candidate
        return len(INDENT) + len(skill.name) + 3 + len(args_text(objects)) + self.robot_arg_len

    def of(self, fn: WrittenFunction) -> list[Candidate]:
        """The action calls whose preconditions the function's own steps do not rule out.

        Put, drop and throw only what the function holds; pick up what it does not hold, and act
        otherwise only on what it does not hold (in a team, the holder would need that skill too);
        slice only with a knife in hand; do not switch on what it switched on (or open
        what it opened), and do not undo the step just taken. If nothing is left, any action.
        """
        key = (frozenset(fn.held), tuple(sorted(fn.states.items())), fn.last_call)
        if key not in self._cache:
            self._cache[key] = list(self._filtered(fn)) or list(self._filtered(None))
        return self._cache[key]

    def _filtered(self, fn: WrittenFunction | None) -> Iterator[Candidate]:
        for skill in self.skills:
            if skill.action == "":
                continue
            types = [list(self.scene.types_for(a)) for a in skill.arguments]
            if self.allows is not None:  # what a call asks of its robots depends on its first object
                types[0] = [t for t in types[0] if self.allows(skill.name, (t,))]
            if skill.action in CUTTING:
                types[0] = [t for t in types[0] if t not in self.spared]
            if skill.action == "PickupObject" and self.kept is not None:
                types[0] = [t for t in types[0] if t in self.kept]
            if fn is not None:
                if skill.action in RELEASE_ACTIONS:
                    types[0] = [t for t in types[0] if t in fn.held]
                    if len(types) > 1:
                        types[1] = [t for t in types[1] if t not in fn.held]
                elif skill.action == "PickupObject":
                    types[0] = [t for t in types[0] if t not in fn.held]
                elif skill.action == "SliceObject" and not fn.held & KNIVES:
                    continue
                elif skill.action in STATE_ACTIONS:
                    types[0] = [t for t in types[0] if fn.states.get(t) != skill.action
                                and fn.last_call != (STATE_ACTIONS[skill.action], t)]
                if skill.action not in RELEASE_ACTIONS and skill.action != "PickupObject":
                    # Not on what it holds: in a team, the holder would need this skill too.
                    types[0] = [t for t in types[0] if t not in fn.held]
            for first in types[0]:
                if len(types) == 1:
                    yield skill, (first,)
                    continue
                if skill.required == 1:
                    yield skill, (first,)
                for second in types[1]:
                    yield skill, (first, second)

    def every(self) -> list[Candidate]:
        """Every action call the plan may make, whatever a function has done."""
        return self._every

    def line(self, candidate: Candidate) -> str:
        """A decomposition's line for the call."""
        return call_line(candidate[0].name, candidate[1])

    def node(self, candidates: Sequence[Candidate]) -> Node | None:
        """Call lines for candidates, grouped by skill; None for none."""
        groups: dict[str, list[str]] = {}
        for skill, objects in candidates:
            groups.setdefault(skill.name, []).append(args_text(objects))
        if not groups:
            return None
        robot = [Ref("robot-arg"), ", "] if self.allocated else []
        return alt(*(seq(f"{INDENT}{name}(", *robot, alt(*args), ")\n") for name, args in groups.items()))

    def goto_calls(self) -> list[Candidate]:
        return [(s, (t,)) for s in self.gotos for t in self.scene.types_for(s.arguments[0])
                if self.allows is None or self.allows(s.name, (t,))]

    def goto_node(self, fn: WrittenFunction, room: int, members: list[int]) -> Node | None:
        """The GoToObject lines that leave room for an action after them within ``room`` characters;
        with a world check, only those to a place where one of the function's next calls that fits
        succeeds (for the dry run's robots ``members``)."""
        if self.goto_acts:  # a move is a step in itself: anywhere else it gets to
            here = self.place(fn)
            return self.node([c for c in self.goto_calls() if c[1][0] != here and self.line_len(c) <= room
                              and (self.world is None or self.world.succeeds(members, c[0].name, c[1]))])
        if self.world is None:
            cheapest = min(self.line_len(c) for c in self.of(fn))
            return self.node([c for c in self.goto_calls() if self.line_len(c) + cheapest <= room])
        then = self.of(replace(fn, last_call=("", ""), went=True))
        if fn.steps + 1 >= self.max_steps - 1:  # the step after the go-to is the last: as succeeding
            then = [c for c in then
                    if c[0].action != "PickupObject" and (not fn.held or c[0].action in RELEASE_ACTIONS)]
        gotos = []
        holders = self._holder_types()
        for skill, (target,) in self.goto_calls():
            left = room - self.line_len((skill, (target,)))
            by = {target, None} | holders.get(target, set())
            fitting = [(c.name, objs) for c, objs in then if acts_on((c, objs)) in by
                       and self.line_len((c, objs)) + self.hold_after(fn, (c, objs)) <= left]
            if fitting and self.world.leads_somewhere(members, skill.name, target, fitting):
                gotos.append((skill, (target,)))
        return self.node(gotos)

    def succeeding(self, fn: WrittenFunction, members: list[int]) -> list[Candidate]:
        """The function's allowed calls; with a world check, those that succeed from the state now."""
        candidates = self.of(fn)
        if self.world is None:
            return candidates
        if not fn.went:
            return []
        if fn.steps >= self.max_steps - 1:  # the last step cannot pick up (nothing would put it down)
            candidates = [c for c in candidates if c[0].action != "PickupObject"]
            if fn.held:
                candidates = [c for c in candidates if c[0].action in RELEASE_ACTIONS]
        place = self.place(fn)
        by = {place, None} | (self._holder_types().get(place, set()) if place else set())
        candidates = [c for c in candidates if acts_on(c) in by]
        return [c for c in candidates if self.world.succeeds(members, c[0].name, c[1])]

    def place(self, fn: WrittenFunction, slot: int | None = None) -> str | None:
        """What the function (or its robot_list slot) last went to."""
        gotos = {s.name for s in self.gotos}
        return next((objects[0] for went, skill, objects in reversed(fn.calls)
                     if skill in gotos and went in (slot, None)), None)

    def within_reach(self, fn: WrittenFunction, slot: int | None, target: str | None) -> bool:
        """Whether a restated step of the slot may act on ``target``: nothing (a drop), what the slot last went to,
        or a holder that holds a thing of that type in the dry run now (the planner's steps go to the spray bottle,
        then open "the Cabinet" by it: of four cabinets, the one that holds it)."""
        place = self.place(fn, slot)
        if target in (place, None):
            return True
        return self.world is not None and place is not None and target in self._holder_types().get(place, set())

    def _holder_types(self) -> dict[str, set[str]]:
        """Each type with the types of the holders its things are in, in the dry run now: a call acts on what the
        function last went to, or on a holder of it (by the pan in its cabinet, "the Cabinet" is the pan's, as the
        executor resolves it)."""
        assert self.world is not None
        objects = self.world.objects()
        kinds = {o["objectId"]: o["objectType"] for o in objects}
        holders: dict[str, set[str]] = {}
        for o in objects:
            holders.setdefault(o["objectType"], set()).update(kinds[p] for p in o.get("parentReceptacles") or ()
                                                             if p in kinds)
        return holders

    def hold_after(self, fn: WrittenFunction, candidate: Candidate) -> int:
        """With a world check a function ends with empty hands (its robot may do the next function):
        the reserve for putting down what is held after ``candidate``."""
        if self.world is None or self.allocated:
            return 0
        action = candidate[0].action
        holding = (fn.held and action not in RELEASE_ACTIONS) or action == "PickupObject"
        return self.release_max if holding else 0
