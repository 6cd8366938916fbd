"""The world a plan is written for: which skill calls will succeed from the state the lines so far produce.

While a stage writes a plan line by line, the steps written are applied to an
in-process dry run of the scene (the executor's own decisions, see
:mod:`smartllm_local.executor.dry_run`), and a line is offered only if its call
succeeds there. A decomposition is checked for notional robots with every skill
and no mass limit, one per sub-task (a sub-task's robot holds what it picked up
and nothing another sub-task's robot holds); written for a team, they lift what the whole team lifts together
(:func:`for_decomposition`: a pot with a cup in it weighs both); an allocation for one notional robot
per ``robot_list`` slot (whether a robot has the skill and the strength is the
team feasibility's question). Sub-tasks are checked in the order they are
written; an allocation's threads started together, as the executor interleaves them (see
docs/planner.md, "The world check"). The dry run is the scene's world's (:meth:`.worlds.World.dry_run`): a
site domain's plan is tried on its site simulator the same way.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from ...executor.dry_run import notional_robot
from ...robots import Robot, team_lift
from ...scene import SceneObjects
from ...scoring import Condition, condition_holds, containment
from ...skills import SkillSet
from ...world.object_types import base_type

#: One step of a function: its robot_list slot (None: the whole list), skill and objects.
Call = tuple[int | None, str, tuple[str, ...]]
#: A thread as the executor runs it: a step a tick (None: a second of sleep), and its robot_list (team indices).
Thread = tuple[Sequence[Call | None], Sequence[int]]


class WorldCheck:
    """A dry run of the scene with a team (notional robots unless given), and counts of what it decided."""

    def __init__(self, scene: SceneObjects, skills: SkillSet, agents: int = 1,
                 robots: Sequence[Robot] | None = None):
        self.scene, self.skills = scene, skills
        self.run = scene.world.dry_run(scene.floor_plan, skills, robots, agents)
        self.tries = 0
        self.dead_ends = 0  # lines for which nothing that succeeds could be offered
        self.keep: Sequence[Condition] = ()  # conditions a call must leave holding to count as succeeding

    def succeeds(self, members: Sequence[int], skill: str, objects: Sequence[str]) -> bool:
        self.tries += 1
        if not self.keep:
            return self.run.succeeds(members, skill, objects).success
        saved = self.run.snapshot()
        try:
            return self.run.apply(members, skill, objects).success and self.met(self.keep) == len(self.keep)
        finally:
            self.run.restore(saved)

    def apply(self, members: Sequence[int], skill: str, objects: Sequence[str]) -> None:
        self.run.apply(members, skill, objects)

    def objects(self) -> list[Mapping[str, Any]]:
        """The dry run's objects now, as the scorer reads a final state."""
        return list(self.run.objects)

    def met(self, conditions: Sequence[Condition]) -> int:
        """How many of ``conditions`` hold in the dry run now."""
        objects = self.objects()
        inside = containment(objects)
        return sum(condition_holds(c, objects, inside) for c in conditions)

    def leads_somewhere(self, members: Sequence[int], goto: str, target: str,
                        then: Sequence[tuple[str, Sequence[str]]]) -> bool:
        """Whether, after going to ``target``, one of the calls ``then`` succeeds (so a GoToObject
        is offered only where there is something to do)."""
        saved = self.run.snapshot()
        try:
            self.tries += 1
            if not self.run.apply(members, goto, [target]).success:
                return False
            return any(self.succeeds(members, skill, objects) for skill, objects in then)
        finally:
            self.run.restore(saved)

    def runs(self, calls: Sequence[Call], robots: Sequence[int]) -> bool:
        """Whether a function's calls all succeed with ``robots`` (team indices) as its robot_list."""
        saved = self.run.snapshot()
        try:
            return all(self._call(call, robots) for call in calls)
        finally:
            self.run.restore(saved)

    def perform(self, calls: Sequence[Call], robots: Sequence[int]) -> bool:
        """Apply a function's calls with ``robots`` as its robot_list (all of them, as the executor goes
        on after a failure); whether they all succeeded."""
        return all([self._call(call, robots) for call in calls])

    def runs_together(self, threads: Sequence[Thread]) -> bool:
        """Whether threads started together all succeed in every call, run as the executor runs them."""
        saved = self.run.snapshot()
        try:
            return self.perform_together(threads, stop=True)
        finally:
            self.run.restore(saved)

    def perform_together(self, threads: Sequence[Thread], *, stop: bool = False) -> bool:
        """Apply threads started together as the executor runs them: at each tick the next step of each thread
        that has one, in launch order (the same steps applied one after the other would not give the state they
        meet); whether every call succeeded (with ``stop``, up to the first that fails)."""
        ok = True
        for tick in range(max((len(steps) for steps, _ in threads), default=0)):
            for steps, robots in threads:
                if tick < len(steps) and steps[tick] is not None:
                    ok = self._call(steps[tick], robots) and ok  # type: ignore[arg-type]
                    if stop and not ok:
                        return False
        return ok

    def _call(self, call: Call, robots: Sequence[int]) -> bool:
        slot, skill, objects = call
        self.tries += 1
        return self.run.apply(list(robots) if slot is None else [robots[slot]], skill, objects).success


def held(objects: Sequence[Mapping[str, Any]]) -> set[tuple[str, str]]:
    """(thing's type, its direct holder's type) for every thing in a holder, a slice counted as its whole."""
    by_id = {o["objectId"]: o for o in objects}
    return {(base_type(by_id[child]["objectType"]), o["objectType"])
            for o in objects for child in o.get("receptacleObjectIds") or () if child in by_id}


def for_decomposition(scene: SceneObjects, skills: SkillSet, agents: int,
                      team: Sequence[Robot] | None = None) -> WorldCheck:
    """A decomposition's world check: ``agents`` notional robots, each lifting what the whole ``team`` lifts together
    (no limit without a team). No coalition lifts more, and the world weighs a thing with what it holds: the 0.5B
    put the cup in a pot, and the planner's last sub-task carried the pot, 0.97 kg, for a robot of 0.9 (dev5-e6)."""
    lift = team_lift(team) if team else math.inf
    return WorldCheck(scene, skills, robots=[notional_robot(skills, lift)] * agents)
