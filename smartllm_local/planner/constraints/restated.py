"""Stage 3 restating stage 1: the allocation writes the decomposition's steps itself.

In SMART-LLM's allocated examples the steps are the decomposition's, with robots
added. Here the comments and sleeps of each function are forced text and each
skill call is offered with its robot argument left open, so the model chooses only
the robot of each step and the orchestration: a plan cannot drift between stages,
and its longest output is known to the character (its budget).

With a world check, a robot argument is offered only if the call succeeds for
that ``robot_list`` slot where the slots stand (notional robots, one per slot)
and leaves every later step of the body a robot under which it succeeds (a search
over the rest of the body, so that a robot chosen early cannot strand a later
step); and a robot list only if every step of the function succeeds with the team's own robots from the state the
functions launched before it leave, as the executor decides it (skills, mass,
reach, team lifting); a thread joining an open block, run together with the block's
threads as the executor interleaves them.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import replace

from ...robots import Robot
from ...scene import SceneObjects
from ...skills import Skill, SkillSet
from ..decoding.grammar import alt, seq
from ..decoding.protocol import Choose, Forced
from .candidates import acts_on
from .feasibility import Step, feasible_lists, one_robot_suffices
from .format import INDENT
from .plan import STEP_LINE, PlanConstraint
from .world_check import Call, Thread, WorldCheck
from .written import WrittenFunction, robots_named, sleep_ticks

#: Robot arguments a search for the rest of a body may try before it gives up (and offers the step).
COMPLETION_TRIES = 400


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
                 function_names: Sequence[str], bodies: Sequence[Sequence[str]], world: WorldCheck | None = None,
                 together: bool = False, chosen: Mapping[str, frozenset[int]] | None = None):
        """``chosen``: the team each function's coalition line chose (:func:`.coalition.chosen_teams`)."""
        if len(bodies) != len(function_names):
            raise ValueError("a restated allocation needs one body per function name")
        self.bodies = [list(body) for body in bodies]
        self.chosen = dict(chosen or {})
        known = {"team": team} if not isinstance(team, int) else {"team_size": team}
        # Refusing is the coalition stage's answer; once teams are formed, the plan is written.
        super().__init__(scene, skills, function_names=function_names, world=world, allow_refusal=False,
                         together=together, **known)
        # Robot lists are checked with the team's own robots, in launch order.
        self.team_world = WorldCheck(world.scene, world.skills, robots=self.team) \
            if world is not None and self.team is not None else None
        # While bodies are written, the team's own robots run each finished body (with the first robot
        # list under which it succeeds), so a body is checked from the state its predecessors leave.
        self.body_world = WorldCheck(world.scene, world.skills, robots=self.team) \
            if self.team_world is not None else None
        self._bodies_run: set[str] = set()
        self._alone: dict[str, bool] = {}  # per function: whether one robot can do its whole body (_one_robot)
        # The open block of threads: the team's dry run where it began, and its threads so far.
        self._block_start: object = None
        self._block: list[Thread] = []

    def _body_cost(self, index: int) -> int:
        return sum(self._line_cost(line) for line in self.bodies[index])

    def _line_cost(self, line: str) -> int:
        return len(line) + (self.robot_arg_len if STEP_LINE.match(line) and "time.sleep" not in line else 0)

    def maximum_output(self) -> int:
        """The longest output: every body with its longest robot arguments, every function in a thread."""
        names = self.fixed_names
        bodies = sum(len(f"def {n}(robot_list):\n") + self._body_cost(k) + 1 for k, n in enumerate(names))
        threads = sum(self.budget.thread_len(n, k + 1) for k, n in enumerate(names))
        return bodies + threads + self.budget.starts_joins(len(names))

    def world_counts(self) -> tuple[int, int]:
        worlds = [w for w in (self.world, self.team_world, self.body_world) if w is not None]
        return sum(w.tries for w in worlds), sum(w.dead_ends for w in worlds)

    def _body(self, remaining: int) -> Forced | Choose:
        """The decomposition's next line: comments and sleeps as they are, a skill call with the robot
        left to the model (only robots that keep a capable robot list possible), then the blank line."""
        fn = self.functions[-1]
        body = self.bodies[len(self.functions) - 1]
        if fn.written == len(body):
            self._run_body(fn)
            return Forced("\n")
        line = body[fn.written]
        call = self._skill_call(line)
        if call is None:
            return Forced(line)
        skill, objects, args = call
        able, working = self._robot_args(fn, skill, objects)
        if self.world is not None and working:
            # Only robots after whose step the rest of the body can still be done by the team its coalition line
            # chose (two weak robots lifting together beside a strong one's thread: dev12-c2), or by some robots
            # where it cannot.
            team = self.chosen.get(fn.name)
            kept = [a for a in working if self._completes(fn, a, skill, objects, team)] if team else []
            found = [] if kept else [(a, self._completes(fn, a, skill, objects)) for a in working]
            working = kept or [a for a, ok in found if ok] or [a for a, ok in found if ok is None]
            if self.joins:  # a robot the sub-task can do without stays free for another thread
                working = [a for a in working if not self._new_slot(fn, a)] or working
        if self.world is not None and not working:
            self.world.dead_ends += 1
        # No robot can: the coalition stage refuses such plans, and free teams leave it to the model.
        robots = working or able or self.robot_args
        if self.joins and "robot_list[0]" in robots and self._one_robot(fn):
            robots = ["robot_list[0]"]
        text = seq(f"{INDENT}{skill.name}(", alt(*robots), f", {args})\n")
        return self._choose(self.rules, {"goto" if skill.action == "" else "action": text})

    def _chosen(self, fn: WrittenFunction, lists: list[tuple[int, ...]]) -> list[tuple[int, ...]]:
        """The lists of the team the function's coalition line chose, where any may be given now: the coalition
        decided who does the sub-task, and the allocation writes it (over the whole benchmark the model's
        allocations had named that team for all 66 sub-tasks); every list where none is or none can be."""
        team = self.chosen.get(fn.name)
        return [order for order in lists if frozenset(order) == team] or lists

    def _one_robot(self, fn: WrittenFunction) -> bool:
        """Whether the function's whole body is one robot's work (:func:`.feasibility.one_robot_suffices`). Where
        sub-tasks join threads (``together``), its robot lists are then of one robot, where ``robot_list`` and
        ``robot_list[0]`` name the same robot: each step is written for ``robot_list[0]``, and the model is not
        asked which."""
        if self.team is None:
            return False
        if fn.name not in self._alone:
            calls = filter(None, map(self._skill_call, self.bodies[len(self.functions) - 1]))
            whole = replace(fn, calls=[(0, skill.name, tuple(objects)) for skill, objects, _ in calls])
            self._alone[fn.name] = one_robot_suffices(self.team, self._steps(whole))
        return self._alone[fn.name]

    @staticmethod
    def _new_slot(fn: WrittenFunction, arg: str) -> bool:
        """Whether the robot argument brings a robot into the function beyond those its steps use so far."""
        return arg.startswith("robot_list[") and int(arg[len("robot_list["):-1]) > max(fn.max_index, 0)

    def _skill_call(self, line: str) -> tuple[Skill, list[str], str] | None:
        """A body line's skill, objects and argument text; None for a comment or a sleep."""
        match = STEP_LINE.match(line)
        if match is None or match.group(1) == "time.sleep":
            return None
        return self.by_name[match.group(1)], re.findall(r"'([^']+)'", match.group(2)), match.group(2)

    def _rest(self, fn: WrittenFunction) -> list[tuple[Skill, list[str]]]:
        """The restated body's skill calls after the current line."""
        calls = (self._skill_call(line) for line in self.bodies[len(self.functions) - 1][fn.written + 1:])
        return [(skill, objects) for skill, objects, _ in filter(None, calls)]

    def _completes(self, fn: WrittenFunction, arg: str, skill: Skill, objects: Sequence[str],
                   team: frozenset[int] | None = None) -> bool | None:
        """Whether, after this step by ``arg``, every later step of the body can be given a robot
        argument under which it succeeds (a depth-first search, the last step's robot tried first), run by
        ``team`` where one is given; None if the search ran out of tries before it knew."""
        budget = [COMPLETION_TRIES]
        saved = self.world.run.snapshot()
        try:
            trial = self._after(fn, arg, skill, objects)
            return self._search(trial, self._rest(fn), arg, budget, team)
        finally:
            self.world.run.restore(saved)

    def _search(self, fn: WrittenFunction, rest: Sequence[tuple[Skill, list[str]]], last: str,
                budget: list[int], team: frozenset[int] | None = None) -> bool | None:
        if not rest:
            return bool(self._team_lists(fn, budget, team))
        skill, objects = rest[0]
        unknown = False
        args = self._robot_args(fn, skill, objects)[1]
        # The robot of the last step first, then the whole list for a GoToObject (it brings every slot).
        args.sort(key=lambda a: (a != last, not (skill.action == "" and a == "robot_list")))
        for arg in args:
            if budget[0] <= 0:
                return None
            budget[0] -= 1
            saved = self.world.run.snapshot()
            try:
                found = self._search(self._after(fn, arg, skill, objects), rest[1:], arg, budget, team)
            finally:
                self.world.run.restore(saved)
            if found:
                return True
            unknown = unknown or found is None
        return None if unknown else False

    def _team_lists(self, fn: WrittenFunction, budget: list[int] | None = None,
                    team: frozenset[int] | None = None) -> list[tuple[int, ...]]:
        """The robot lists under which the team's own robots do every step of the whole body from the
        state the bodies before it leave (one is enough with a budget), of ``team``'s robots alone where one is
        given; every list without a team."""
        need = self._need(fn)
        lists = feasible_lists(self.team, self._steps(fn), need) if self.team is not None else None
        if team is not None and lists is not None:
            lists = [order for order in lists if frozenset(order) == team]
        if self.body_world is None or lists is None:
            return lists or [tuple(range(need))]
        working = []
        for order in lists:
            if budget is not None:
                if budget[0] <= 0:
                    break
                budget[0] -= 1
            if self.body_world.runs(fn.calls, order):
                working.append(order)
                if budget is not None:
                    break
        return working

    def _team_checks_lists(self) -> bool:
        return self.team_world is not None

    def _run_body(self, fn: WrittenFunction) -> None:
        """Once a body is written, let the team run it (with its first working list) for the next body."""
        if self.body_world is not None and fn.name not in self._bodies_run:
            self._bodies_run.add(fn.name)
            lists = self._team_lists(fn) or feasible_lists(self.team, self._steps(fn), self._need(fn)) or []
            if lists:
                self.body_world.perform(fn.calls, lists[0])

    def _after(self, fn: WrittenFunction, arg: str, skill: Skill, objects: Sequence[str]) -> WrittenFunction:
        """A copy of the function with one more step by ``arg``, applied to the world check's dry run."""
        slot = self._slot(arg)
        trial = replace(fn, slots_went=set(fn.slots_went), calls=list(fn.calls))
        self.world.apply(self._members(trial, slot), skill.name, objects)
        trial.calls.append((slot, skill.name, tuple(objects)))
        trial.max_index = max(trial.max_index, -1 if slot is None else slot)
        if skill.action == "":
            self._mark_went(trial, slot)
        return trial

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
            if slot is not None and slot > fn.max_index + 1:
                continue  # slots are numbered as they first act: robot_list[1] comes after robot_list[0]
            if self.world is not None and skill.action and (
                    not (fn.together if slot is None else slot in fn.slots_went)
                    or not self.candidates.within_reach(fn, slot, acts_on((skill, tuple(objects))))):
                continue  # with a world check, robots act on what they went to in this function (or its holder)
            if self.team is not None:
                demand = self.scene.world.call_demand(skill.name, objects)
                steps = self._steps(fn) + [Step(slot, skill.name, mass, demand)]
                lists = feasible_lists(self.team, steps, max(1, fn.max_index + 1, (slot or 0) + 1))
                if lists is not None and not lists:
                    continue
            able.append(arg)
            if self.world is not None and self.world.succeeds(self._members(fn, slot), skill.name, objects):
                working.append(arg)
        return able, working

    def _working_lists(self, fn: WrittenFunction, lists: list[tuple[int, ...]]) -> list[tuple[int, ...]]:
        """With a world check, the lists under which every step of the function succeeds from the state
        the functions launched before it leave; if none does, all of them (a dead end, counted). In an open
        block of threads, the lists under which it and every thread of the block succeed, run together as the
        executor runs them (a step of each a tick); if none, none: it waits for the block to end."""
        if self.team_world is None:
            return lists
        if self.threads:
            return [order for order in lists if self._runs_in_block(fn, order)]
        working = [order for order in lists if self.team_world.runs(fn.calls, order)]
        self.team_world.dead_ends += not working
        return working or lists

    def _runs_in_block(self, fn: WrittenFunction, order: tuple[int, ...]) -> bool:
        run = self.team_world.run  # type: ignore[union-attr]
        saved = run.snapshot()
        try:
            run.restore(self._block_start)  # type: ignore[arg-type]
            return self.team_world.runs_together([*self._block, (self._timeline(fn), order)])  # type: ignore[union-attr]
        finally:
            run.restore(saved)

    def _timeline(self, fn: WrittenFunction) -> list[Call | None]:
        """The function's steps as the executor runs them: its calls, and a second of nothing for each second
        it sleeps."""
        calls = iter(fn.calls)
        steps: list[Call | None] = []
        for line in self.bodies[self.fixed_names.index(fn.name)]:
            if ticks := sleep_ticks(line):
                steps += [None] * ticks
            elif self._skill_call(line):
                steps.append(next(calls))
        return steps

    def _launch(self, name: str, piece: str) -> None:
        """Run a launched function's steps in the team's dry run, with the robot list the line gives: called
        directly, after what ran before it; as a thread, together with the threads of its block."""
        if self.team_world is None:
            return
        fn = next(f for f in self.functions if f.name == name)
        if "threading.Thread" not in piece:
            self.team_world.perform(fn.calls, robots_named(piece))
            return
        if not self.threads:  # it opens a block
            self._block_start, self._block = self.team_world.run.snapshot(), []
        self._block.append((self._timeline(fn), robots_named(piece)))
        self.team_world.run.restore(self._block_start)
        self.team_world.perform_together(self._block)
