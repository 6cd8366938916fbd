"""Stage 3 restating stage 1: the allocation writes the decomposition's steps itself.

In SMART-LLM's allocated examples the steps are the decomposition's, with robots
added. Here the comments and sleeps of each function are forced text and each
skill call is offered with its robot argument left open, so the model chooses only
the robot of each step and the orchestration: a plan cannot drift between stages,
and its longest output is known to the character (its budget).

With a world check, a robot argument is offered only if the call succeeds for
that ``robot_list`` slot where the slots stand (notional robots, one per slot,
with one step of look-ahead after a GoToObject), and a robot list only if every
step of the function succeeds with the team's own robots from the state the
functions launched before it leave, as the executor decides it (skills, mass,
reach, team lifting).
"""

from __future__ import annotations

import re
from dataclasses import replace
from typing import Sequence

from ..robots import Robot
from ..skills import Skill, SkillSet
from .constraints import INDENT, Choose, Forced
from .feasibility import Step, feasible_lists
from .grammar import alt, seq
from .plan_constraint import STEP_LINE, PlanConstraint, WrittenFunction
from .scene_context import SceneObjects
from .world_check import WorldCheck


def restated_bodies(decomposition: str, names: Sequence[str]) -> list[list[str]]:
    """The body lines (comments, skill calls, sleeps) of each named function of a decomposed plan."""
    bodies: dict[str, list[str]] = {}
    current: list[str] | None = None
    for line in decomposition.splitlines(keepends=True):
        if line.startswith("def "):
            current = bodies.setdefault(line[4:line.index("(")], [])
        elif line.startswith(INDENT) and current is not None:
            current.append(line if line.endswith("\n") else line + "\n")
        else:
            current = None
    return [bodies[name] for name in names]


class RestatedAllocation(PlanConstraint):
    """An allocated plan whose function bodies are the decomposition's, robots left to the model."""

    def __init__(self, scene: SceneObjects, skills: SkillSet, *, team: Sequence[Robot] | int,
                 function_names: Sequence[str], bodies: Sequence[Sequence[str]], world: WorldCheck | None = None):
        if len(bodies) != len(function_names):
            raise ValueError("a restated allocation needs one body per function name")
        self.bodies = [list(body) for body in bodies]
        known = {"team": team} if not isinstance(team, int) else {"team_size": team}
        # Refusing is the coalition stage's answer; once teams are formed, the plan is written.
        super().__init__(scene, skills, function_names=function_names, world=world, allow_refusal=False, **known)
        # Robot lists are checked with the team's own robots, in launch order.
        self.team_world = WorldCheck(world.floor_plan, world.skills, robots=self.team) \
            if world is not None and self.team is not None else None

    def _body_cost(self, index: int) -> int:
        return sum(self._line_cost(line) for line in self.bodies[index])

    def _line_cost(self, line: str) -> int:
        return len(line) + (self.robot_arg_len if STEP_LINE.match(line) and "time.sleep" not in line else 0)

    def maximum_output(self) -> int:
        """The longest output: every body with its longest robot arguments, every function in a thread."""
        names = self.fixed_names
        bodies = sum(len(f"def {n}(robot_list):\n") + self._body_cost(k) + 1 for k, n in enumerate(names))
        threads = sum(self._thread_len(n, k + 1) for k, n in enumerate(names))
        return bodies + threads + self._starts_joins(len(names))

    def world_counts(self) -> tuple[int, int]:
        worlds = [w for w in (self.world, self.team_world) if w is not None]
        return sum(w.tries for w in worlds), sum(w.dead_ends for w in worlds)

    def _body(self, remaining: int) -> Forced | Choose:
        """The decomposition's next line: comments and sleeps as they are, a skill call with the robot
        left to the model (only robots that keep a capable robot list possible), then the blank line."""
        fn = self.functions[-1]
        body = self.bodies[len(self.functions) - 1]
        if fn.written == len(body):
            return Forced("\n")
        line = body[fn.written]
        match = STEP_LINE.match(line)
        if match is None or match.group(1) == "time.sleep":
            return Forced(line)
        skill = self.by_name[match.group(1)]
        objects = re.findall(r"'([^']+)'", match.group(2))
        able, working = self._robot_args(fn, skill, objects)
        if self.world is not None and skill.action == "" and len(working) > 1:
            # Look one step ahead: send robots where one of them can then do the next action.
            following = self._next_action(fn)
            if following is not None:
                working = [a for a in working if self._leads_on(fn, a, skill, objects, *following)] or working
        if self.world is not None and not working:
            self.world.dead_ends += 1
        # No robot can: the coalition stage refuses such plans, and free teams leave it to the model.
        robots = working or able or self.robot_args
        text = seq(f"{INDENT}{skill.name}(", alt(*robots), f", {match.group(2)})\n")
        return self._choose(self.rules, {"goto" if skill.action == "" else "action": text})

    def _next_action(self, fn: WrittenFunction) -> tuple[Skill, list[str]] | None:
        """The restated body's next step after the current one, if it is an action (not a GoToObject)."""
        for line in self.bodies[len(self.functions) - 1][fn.written + 1:]:
            match = STEP_LINE.match(line)
            if match is None or match.group(1) == "time.sleep":
                continue
            skill = self.by_name[match.group(1)]
            return (skill, re.findall(r"'([^']+)'", match.group(2))) if skill.action else None
        return None

    def _leads_on(self, fn: WrittenFunction, arg: str, goto: Skill, objects: Sequence[str],
                  skill: Skill, following: Sequence[str]) -> bool:
        """Whether, after this GoToObject by ``arg``, some robot argument can do the next action."""
        assert self.world is not None
        saved = self.world.run.snapshot()
        trial = replace(fn, slots_went=set(fn.slots_went), calls=list(fn.calls))
        try:
            self._went(trial, arg, goto, objects)
            return bool(self._robot_args(trial, skill, following)[1])
        finally:
            self.world.run.restore(saved)

    def _went(self, fn: WrittenFunction, arg: str, goto: Skill, objects: Sequence[str]) -> None:
        slot = self._slot(arg)
        self.world.apply(self._members(fn, slot), goto.name, objects)
        fn.calls.append((slot, goto.name, tuple(objects)))
        fn.max_index = max(fn.max_index, -1 if slot is None else slot)
        self._mark_went(fn, slot)

    @staticmethod
    def _slot(arg: str) -> int | None:
        return int(arg[len("robot_list["):-1]) if "[" in arg else None

    def _robot_args(self, fn: WrittenFunction, skill: Skill, objects: Sequence[str]) -> tuple[list[str], list[str]]:
        """Robot arguments that leave some robot list able to do every step so far (skills, strength),
        and of those, with a world check, the ones under which the call succeeds where the slots stand."""
        mass = self.scene.masses.get(objects[0], 0.0) if skill.action == "PickupObject" and objects else 0.0
        able, working = [], []
        for arg in self.robot_args:
            slot = self._slot(arg)
            if self.world is not None and skill.action and not (fn.together if slot is None else slot in fn.slots_went):
                continue  # with a world check, robots act where they went in this function, not before it
            if self.team is not None:
                steps = self._steps(fn) + [Step(slot, skill.name, mass)]
                lists = feasible_lists(self.team, steps, max(1, fn.max_index + 1, (slot or 0) + 1))
                if lists is not None and not lists:
                    continue
            able.append(arg)
            if self.world is not None and self.world.succeeds(self._members(fn, slot), skill.name, objects):
                working.append(arg)
        return able, working

    def _working_lists(self, fn: WrittenFunction, lists: list[tuple[int, ...]]) -> list[tuple[int, ...]]:
        """With a world check, the lists under which every step of the function succeeds from the state
        the functions launched before it leave; if none does, all of them (a dead end, counted)."""
        if self.team_world is None:
            return lists
        working = [order for order in lists if self.team_world.runs(fn.calls, order)]
        self.team_world.dead_ends += not working
        return working or lists

    def _launch(self, name: str, piece: str) -> None:
        """Run a launched function's steps in the team's dry run, with the robot list the line gives."""
        if self.team_world is not None:
            fn = next(f for f in self.functions if f.name == name)
            self.team_world.perform(fn.calls, [int(i) for i in re.findall(r"robots\[(\d+)\]", piece)])
