"""Repair inside the SMART-LLM method: the steps that enable a call the model wrote, found by the planner.

With a world check, a decomposition's body offers the calls that succeed where the function stands. A model
that means to slice the bread with no knife in hand would then write something else (it picks the bread up, and
nothing is sliced). So the body also offers the calls that fail now, and when the model writes one, the planner
looks for the shortest steps that make it succeed: the call's effect is stated as the scorer's condition (slice
X: X sliced; put X in R: R holds X), Fast Downward (through Unified Planning, :mod:`..classical`) plans for the
function's robot from the dry run's state now, standing where it stands and holding what it holds. The plan is
a repair when its last step is the model's call, it has at most :data:`MOST_STEPS` steps before it, and every
step succeeds in the dry run as written. The steps are written before the model's line (the planner's lines,
recorded as such); where there is no repair, the line is taken back and the model writes another.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace

from ...errors import SmartLLMError
from ...executor.dry_run import DryRun
from ...scoring import Condition, condition_holds, containment
from ...skills import Skill, SkillSet
from ...world.object_types import base_type
from .candidates import Candidate, Candidates, acts_on, lets_go
from .feasibility import WholeTeam
from .world_check import WorldCheck
from .written import CALL_LINE, WrittenFunction

#: The most steps a repair writes before the model's call (a hand freed and a knife fetched take five), and the more
#: it may write to put what the hand held where a stated goal puts it (go there, open it, put it in).
MOST_STEPS = 5
PUT_AWAY_STEPS = 3
#: Fast Downward's processor time for one search (a repair, or the planner's last sub-task), whole seconds: its
#: translator and search take 0.15-0.4 s of CPU on the household tasks (measured), so the bound is never reached
#: there; being processor time, not the wall clock, it ends a search at the same point however loaded the machine
#: is, so a greedy plan does not change with the load. A search that reaches it finds no repair.
CPU_LIMIT = 10
#: The wall-clock limit on the same search: a backstop against a stuck process only, far above CPU_LIMIT so that
#: load alone never reaches it. Reaching it is an error (:class:`SearchWallClockError`), never a silent "no repair",
#: since where it ended would depend on the load.
TIME_LIMIT = 300.0
#: The most plans sought for one repair, each with only the fixtures the last went to of the types where it went to
#: others than the planner meant (:meth:`Repairer._written`).
ROUNDS = 3
#: A call as a plan writes it: the skill's name and the object types.
Written = tuple[str, tuple[str, ...]]
#: The state each action's effect is, as the scorer names it.
EFFECTS = {"SliceObject": "SLICED", "ToggleObjectOn": "ON", "ToggleObjectOff": "OFF", "OpenObject": "OPENED",
           "CloseObject": "CLOSED", "BreakObject": "BROKEN", "CleanObject": "CLEAN", "PickupObject": "PICKED"}


def effect(skill: Skill, objects: Sequence[str]) -> Condition | None:
    """What holds once the call succeeds, as a goal condition; None where no condition says it (a drop)."""
    if skill.action == "PutObject" and len(objects) == 2:
        return Condition(objects[1], item=objects[0])
    state = EFFECTS.get(skill.action)
    return Condition(objects[0], state=state) if state and objects else None


def repairable(skill: Skill) -> bool:
    """Whether a call of the skill can be repaired (its effect is a condition the planner can aim at)."""
    return skill.action == "PutObject" or skill.action in EFFECTS


class SearchWallClockError(SmartLLMError, RuntimeError):
    """A repair's search ran past its wall-clock backstop before its processor-time limit (a stuck process, or
    a machine far too loaded to plan on)."""


@dataclass(frozen=True)
class Repair:
    """The planner's calls written before the model's (each a skill and its object types), and the search's time."""

    calls: tuple[Written, ...]
    seconds: float


@dataclass(frozen=True)
class Planned:
    """Fast Downward's plan as a plan may write it (each way), the search's time, and the fixtures it meant by
    each type written (a knob by the one thing it switches)."""

    written: list[list[Written]]
    seconds: float
    meant: dict[str, set[str]]


class Repairer:
    """Finds repairs for the calls of one decomposition (a dry run of the household world)."""

    @staticmethod
    def fits(world: WorldCheck) -> bool:
        """Whether repair can plan in the world check's dry run (the AI2-THOR world's rules, its planning model)."""
        return isinstance(world.run, DryRun)

    def __init__(self, world: WorldCheck, skills: SkillSet, time_limit: float = TIME_LIMIT,
                 cpu_limit: int = CPU_LIMIT, stated: Sequence[Condition] = ()):
        """``stated``: the goals the model stated, whose holders a repair puts the things it frees a hand of in."""
        if not self.fits(world):
            raise ValueError("repair plans in the household world's dry run")
        self.run, self.skills, self.time_limit, self.cpu_limit = world.run, skills, time_limit, cpu_limit
        self.stated = tuple(stated)

    def enable(self, member: int, place: str | None, skill: Skill, objects: Sequence[str],
               allows: Callable[[str, Sequence[str]], bool] | None = None,
               skills: frozenset[str] | None = None) -> Repair | None:
        """The steps after which ``member``, which last went to ``place``, can make the call, or None (no plan,
        too long, or not as written). ``skills``: what the planner's robot may do (a plan for a team: the team's
        skills); ``allows``: whether the plan may make a call at all (the team's reach and strength)."""
        goal = effect(skill, objects)
        if goal is None:
            return None
        call, put = (skill.name, tuple(objects)), self._put_where_stated(member, objects)
        most = MOST_STEPS + PUT_AWAY_STEPS * len(put)
        found = self._written(member, [goal, *put], place, skills, False, lambda calls: calls[-1] == call
                              and 1 < len(calls) <= most + 1 and self._usable(member, calls, allows))
        return None if found is None else Repair(tuple(found.calls[:-1]), found.seconds)

    def _put_where_stated(self, member: int, objects: Sequence[str]) -> list[Condition]:
        """The stated goals that put the thing ``member`` holds somewhere, where the call does not act on it: a
        repair that frees the hand puts it there (the 0.5B, holding the mug it was to put in the microwave, wrote
        the egg into the fridge, and the repair put the mug in the fridge to free its hand)."""
        held = self.run.world.holding(member)
        if held is None or held["objectType"] in objects:
            return []
        return [c for c in self.stated if c.item is not None and base_type(c.item) == base_type(held["objectType"])]

    def meet(self, member: int, goals: Sequence[Condition], most: int,
             allows: Callable[[str, Sequence[str]], bool] | None = None,
             skills: frozenset[str] | None = None) -> Repair | None:
        """The steps of a new sub-task whose robot ``member`` (one no sub-task has used) meets ``goals`` and ends
        with empty hands, where its ``skills`` can let a thing go, in at most ``most`` steps, or None: asked to
        slice the apple and the lettuce with a robot that picks up and slices and one that opens, the 0.5B sliced
        the apple alone, and no plan that ends with the knife put down was found for the lettuce (dev10-s2)."""
        free = skills is None or lets_go(self.skills[s] for s in skills if s in self.skills)
        return self._written(member, goals, None, skills, free, lambda calls: 0 < len(calls) <= most
                             and self._usable(member, calls, allows, goals))

    def _written(self, member: int, goals: Sequence[Condition], place: str | None, skills: frozenset[str] | None,
                 hands_free: bool, fits: Callable[[list[Written]], bool]) -> Repair | None:
        """The first of Fast Downward's plans, as written, that ``fits``. A type names the instance the executor
        chooses, not the planner's: where no way of writing the plan fits, and the robot went to another fixture
        of a type than the one planned (the burner nearest the sink, cold, for the one switched on; the drawer
        nearest the spray bottle, shut, for the one another robot opened), the planner plans again with only the
        fixtures of that type the robot went to, for at most :data:`ROUNDS` plans in all."""
        went: dict[str, set[str]] = {}
        seconds = 0.0
        for _ in range(ROUNDS):
            others = frozenset(o["objectId"] for o in self.run.objects
                               if o["objectType"] in went and o["objectId"] not in went[o["objectType"]])
            found = self._plan(member, goals, place, skills, hands_free, others)
            if found is None:
                return None
            seconds += found.seconds
            calls = next((calls for calls in found.written if fits(calls)), None)
            if calls is not None:
                return Repair(tuple(calls), round(seconds, 3))
            elsewhere = self._went_elsewhere(member, found.written[0], found.meant)
            if all(ids <= went.get(kind, set()) for kind, ids in elsewhere.items()):
                return None
            for kind, ids in elsewhere.items():
                went.setdefault(kind, set()).update(ids)
        return None

    def _went_elsewhere(self, member: int, calls: Sequence[Written],
                        meant: Mapping[str, set[str]]) -> dict[str, set[str]]:
        """The fixtures, by type, that the calls' GoToObject steps reach in the dry run (up to the first that
        fails) where the planner meant another of that type."""
        saved = self.run.snapshot()
        elsewhere: dict[str, set[str]] = {}
        try:
            for name, objects in calls:
                outcome = self.run.apply([member], name, objects)
                if not outcome.success:
                    break
                kind = objects[0] if objects else ""
                if self.skills[name].action == "" and kind in meant and outcome.object_id not in meant[kind]:
                    elsewhere.setdefault(kind, set()).add(outcome.object_id or "")
        finally:
            self.run.restore(saved)
        return elsewhere

    def _plan(self, member: int, goals: Sequence[Condition], place: str | None, skills: frozenset[str] | None,
              hands_free: bool = False, leave_out: frozenset[str] = frozenset()) -> Planned | None:
        """Fast Downward's shortest plan for ``member`` from the dry run's state now, as a plan may write it: going
        to each place it acts at, and then (where that differs) going to the thing it takes out of a shut holder,
        or puts something in there, before opening the holder. A type names the instance nearest the robot: by the
        thing, the holder that holds it; by "the Cabinet", any of four (the spray bottle's cabinet was not the one
        the plan went to). The
        fixtures ``leave_out`` are not the planner's to use (:func:`..classical.problem.planning_task`)."""
        # Unified Planning takes most of a second to import: it loads with the first repair sought, not every plan
        from ..classical.problem import Unreachable, planning_task, with_future_pieces
        from ..classical.search import UP_LOCK, search

        started = time.perf_counter()
        robot = self.run.team[member]
        if skills is not None:
            robot = replace(robot, skills=robot.skills & skills)
        with UP_LOCK:
            try:
                task = planning_task(self.run, [robot], self.skills, goals, name="repair", members=[member],
                                     hands_free=hands_free, leave_out=leave_out)
            except Unreachable:
                return None
            found = search(task, self.time_limit, cpu_limit=self.cpu_limit)
        seconds = round(time.perf_counter() - started, 3)
        if found.timed_out and not found.out_of_cpu:
            raise SearchWallClockError(
                f"Fast Downward's search for a repair ran {seconds:g} s of wall-clock time without reaching its "
                f"{self.cpu_limit} s of processor time (the backstop is {self.time_limit:g} s): the machine is too "
                "loaded to plan on, or Fast Downward is stuck; run again with fewer processes at once, or with "
                "--no-repair and --no-finish-goals")
        if not found.found or not found.steps:
            return None
        objects = with_future_pieces(self.run.objects)[0]  # slices to come
        types = {o["objectId"]: o["objectType"] for o in objects}
        # A switch of one thing is written as the thing (the executor switches a StoveBurner by its knob): a plan
        # names types, and the StoveKnob nearest the robot need not be the one the planner meant.
        switched = {o["objectId"]: o["controlledObjects"][0] for o in objects
                    if len(o.get("controlledObjects") or ()) == 1}
        types |= {oid: types.get(thing, types[oid]) for oid, thing in switched.items()}
        steps = [(s.skill, tuple(s.objects)) for s in found.steps]
        calls = [(name, tuple(types.get(o, o) for o in ids)) for name, ids in steps]
        written = [self._gone_first(calls, place)]
        by_thing = self._gone_first(calls, place, self._taken_out(steps, types))
        fixtures = {o["objectId"] for o in objects if not o.get("pickupable")}
        meant: dict[str, set[str]] = {}
        for oid in {oid for _, ids in steps for oid in ids} & fixtures:
            meant.setdefault(types[oid], set()).add(switched.get(oid, oid))
        return Planned(written + ([by_thing] if by_thing != written[0] else []), seconds, meant)

    def _taken_out(self, steps: Sequence[tuple[str, tuple[str, ...]]], types: dict[str, str]) -> list[str | None]:
        """For each step that opens a holder, and the step going there just before it, the type of the first thing
        in it (where it holds it now) that a later step picks up or puts something in: the egg for the pan went in
        the pan in its shut cabinet, and "the Cabinet" gone to by type was another of eleven; None for every other
        step."""
        holds = {o["objectId"]: set(o.get("receptacleObjectIds") or ()) for o in self.run.objects}
        where: list[str | None] = [None] * len(steps)
        for n, (name, ids) in reversed(list(enumerate(steps))):
            if self.skills[name].action == "OpenObject" and ids:
                inside = holds.get(ids[0], set())
                where[n] = next((types.get(used, used) for skill, later in steps[n + 1:]
                                 if (used := self._used(skill, later)) in inside), None)
            elif self.skills[name].action == "" and n + 1 < len(steps) and steps[n + 1][1][:1] == ids[:1]:
                where[n] = where[n + 1]
        return where

    def _used(self, name: str, ids: Sequence[str]) -> str | None:
        """The thing a step takes out of where it is, or puts something in: a pickup's thing, a put's holder."""
        action = self.skills[name].action
        return ids[0] if action == "PickupObject" and ids else ids[1] if action == "PutObject" and len(ids) > 1 \
            else None

    def _usable(self, member: int, calls: Sequence[Written], allows: Callable[[str, Sequence[str]], bool] | None,
                goals: Sequence[Condition] = ()) -> bool:
        """Whether the plan may make every call (the team's reach and strength), and they succeed as written and
        leave the ``goals`` met (the instance a type names is the executor's choice, not the planner's)."""
        return (allows is None or all(allows(name, objs) for name, objs in calls)) \
            and self._succeeds(member, calls, goals)

    def _gone_first(self, calls: Sequence[Written], place: str | None,
                    where: Sequence[str | None] = ()) -> list[Written]:
        """The calls as a decomposition writes them: each action where the function last went (a GoToObject
        before one that acts elsewhere: the planner's robot stands by all it sees, a plan's robot surely only
        by what it went to; for the n-th call, to ``where[n]`` where given), and no GoToObject to where it already
        is."""
        goto = next(s.name for s in self.skills.values() if s.action == "")
        written: list[Written] = []
        for n, (name, objects) in enumerate(calls):
            skill = self.skills[name]
            target = objects[0] if skill.action == "" else acts_on((skill, objects))
            target = where[n] if n < len(where) and where[n] is not None else target
            if target is not None and target != place:
                written.append((goto, (target,)))
                place = target
            if skill.action != "":
                written.append((name, objects))
        return written

    def _succeeds(self, member: int, calls: Sequence[Written], goals: Sequence[Condition] = ()) -> bool:
        """Whether the calls, as written (object types, resolved as the executor resolves them), all succeed and
        leave the ``goals`` met."""
        saved = self.run.snapshot()
        try:
            if not all(self.run.apply([member], name, objects).success for name, objects in calls):
                return False
            objects = list(self.run.objects)
            inside = containment(objects)
            return all(condition_holds(c, objects, inside) for c in goals)
        finally:
            self.run.restore(saved)


class Repairs:
    """A decomposition's repairs: the failing calls its body offers, and what is written for the one the model
    chose (``made``: each repair, the model's line and the planner's before it; ``missed``: the lines, by
    function and step, the planner could not enable, not offered there again)."""

    def __init__(self, repairer: Repairer, candidates: Candidates, whole: WholeTeam | None, max_steps: int,
                 skills: dict[str, Skill]):
        self.repairer, self.candidates, self.whole, self.max_steps, self.skills = \
            repairer, candidates, whole, max_steps, skills
        self.made: list[dict[str, object]] = []
        self.missed: set[tuple[int, int, str]] = set()

    def offered(self, k: int, fn: WrittenFunction, succeeding: Sequence[Candidate], room: int) -> list[Candidate]:
        """The calls that fail where function ``k`` stands and that a repair may enable in the room there is: its
        steps, the call, and putting down what is held after it (each at its longest line)."""
        if fn.steps + MOST_STEPS + 2 > self.max_steps:
            return []
        calls = self.candidates
        room -= MOST_STEPS * max(calls.goto_max, calls.action_max) + calls.release_max
        done = set(succeeding)
        return [c for c in calls.every() if c not in done and repairable(c[0]) and calls.line_len(c) <= room
                and (k, fn.steps, calls.line(c)) not in self.missed]

    def rewrite(self, k: int, fn: WrittenFunction, member: int, line: str) -> str:
        """What is written for the model's ``line`` in function ``k`` (its dry run's robot ``member``): the
        planner's steps and the line, or nothing (the line is taken back)."""
        match = CALL_LINE.match(line.rstrip("\n"))
        assert match is not None  # a repairable line is a call line
        objects = tuple(o for o in match.group(3, 4) if o is not None)
        whole = self.whole
        found = self.repairer.enable(member, self.candidates.place(fn), self.skills[match.group(1)], objects,
                                     allows=whole.can if whole else None, skills=whole.skills if whole else None)
        if found is None:
            self.missed.add((k, fn.steps, line))
            return ""
        lines = [self.candidates.line((self.skills[name], objs)) for name, objs in found.calls]
        self.made.append({"line": line, "before": lines, "seconds": found.seconds})
        return "".join(lines) + line
