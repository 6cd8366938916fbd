"""The interpreter: runs a plan's IR with a team, in ticks, reproducibly.

The main flow (the plan's top level) launches sub-tasks: ``t.start()`` launches
a thread, a direct call launches one and waits for it. Every tick, each running
sub-task advances by one step (a skill call, or one second of ``time.sleep``),
in launch order, so parallel work really overlaps and a run is the same every
time. A sub-task claims the robots it uses when it starts; one launched while
another holds any of its robots waits until they are free.

Transitions (for the RU metric): a transition happens when one group of
concurrently working robots finishes and another group takes over. Measured
on the run, a group is the set of sub-tasks that begin working in the same
tick, so ``transitions = (number of distinct ticks at which sub-tasks begin) -
1``. A sequential plan of three sub-tasks has 2, three threads started
together have 0, two parallel then one more have 1; sub-tasks written as
parallel but sharing a robot run one after another and count as separate
groups.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

from ..errors import UserError
from ..plan_language.ir import (
    Call,
    Function,
    Join,
    NewThread,
    Plan,
    RobotIndexError,
    SkillCall,
    Sleep,
    Start,
    bind,
    resolve_robots,
)
from ..robots import Robot
from ..skills import DEFAULT_SKILL_SET, Skill, SkillSet
from .team_actions import Outcome, TeamWorld

DEFAULT_MAX_TICKS = 20_000
Env = dict[str, tuple[int, ...]]


@dataclass
class TraceEntry:
    """One primitive action of the run."""

    tick: int
    subtask: str
    robots: list[int]  # catalogue ids
    skill: str
    objects: list[str]
    action: str  # the AI2-THOR action that carried it out
    object_id: str | None
    success: bool
    error: str
    positions: list[tuple[float, float]] | None = None  # (x, z) of each of ``robots`` after the action
    object_position: tuple[float, float] | None = None  # (x, z) of ``object_id`` after the action
    line: int = 0  # the plan's line of the skill call (1-based)

    def as_dict(self) -> dict[str, Any]:
        """The entry as ``execute --trace`` writes it, with AI2-THOR's names for the action's fields (and the
        positions, where the world has them)."""
        entry = {"tick": self.tick, "subtask": self.subtask, "robots": list(self.robots), "skill": self.skill,
                 "objects": list(self.objects), "action": self.action, "objectId": self.object_id,
                 "success": self.success, "errorMessage": self.error}
        if self.positions is not None:
            entry["positions"] = [list(p) for p in self.positions]
        if self.object_position is not None:
            entry["objectPosition"] = list(self.object_position)
        return entry


@dataclass
class Execution:
    """What a run did: its trace, its structure, and the world's final objects."""

    trace: list[TraceEntry]
    transitions: int
    ticks: int
    starts: list[tuple[str, int]]  # (sub-task, tick it began working)
    final_objects: list[dict[str, Any]] = field(repr=False)
    truncated: bool = False
    layout: dict[str, Any] | None = field(default=None, repr=False)  # the world's floor, for a map (None: none)

    @property
    def attempted(self) -> int:
        return len(self.trace)

    @property
    def succeeded(self) -> int:
        return sum(1 for e in self.trace if e.success)


_END = object()


@dataclass
class _Task:
    name: str
    steps: Iterator[tuple[SkillCall, tuple[int, ...]] | None]
    robots: frozenset[int]
    began_at: int | None = None
    done: bool = False
    upcoming: Any = None  # the next step, read ahead so a task is known finished as soon as it is

    def advance(self) -> Any:
        step, self.upcoming = self.upcoming, next(self.steps, _END)
        return step


def _expand(plan: Plan, fn: Function, env: Env, team_size: int) -> Iterator[tuple[SkillCall, tuple[int, ...]] | None]:
    """A sub-task's steps in order: (skill call, its robots), or None for each idle second."""
    for step in fn.body:
        if isinstance(step, SkillCall):
            assert step.robots is not None
            yield step, resolve_robots(step.robots, env, team_size)
        elif isinstance(step, Sleep):
            for _ in range(math.ceil(step.seconds)):
                yield None
        else:
            callee = plan.by_name[step.function]
            yield from _expand(plan, callee, bind(callee, step.args, env, team_size), team_size)


def _robots_used(plan: Plan, fn: Function, env: Env, team_size: int) -> frozenset[int]:
    used: set[int] = set()
    for step in fn.body:
        if isinstance(step, SkillCall) and step.robots is not None:
            used.update(resolve_robots(step.robots, env, team_size))
        elif isinstance(step, Call):
            callee = plan.by_name[step.function]
            used |= _robots_used(plan, callee, bind(callee, step.args, env, team_size), team_size)
    return frozenset(used)


def execute(
    plan: Plan,
    controller: Any,
    team: Sequence[Robot],
    *,
    skills: SkillSet = DEFAULT_SKILL_SET,
    max_ticks: int = DEFAULT_MAX_TICKS,
    object_filter: bool = True,
) -> Execution:
    """Run an allocated plan with ``team`` through ``controller`` (its agents are the team, in order).

    ``object_filter`` has the agents report only the objects the plan can involve while it
    runs (:mod:`.focus`): the same run, with much less metadata to decode.

    Raises:
        UserError: the plan is decomposed (it names no robots) or names robots outside the team.
    """
    check_team(plan, len(team))
    names = {name for call in plan.skill_calls() for name in call.objects} if object_filter else None
    return run(plan, TeamWorld(controller, team, skills, focus=names), team, skills=skills, max_ticks=max_ticks)


def check_team(plan: Plan, team_size: int) -> None:
    """Refuse, before anything runs, a decomposed plan or one naming robots outside the team (a plan
    validated without the team may still name robots it does not have)."""
    if plan.form != "allocated":
        raise UserError("only allocated plans (whose skill calls name robots) can be executed")
    try:
        for step in plan.main:
            if isinstance(step, (Call, NewThread)):
                fn = plan.by_name[step.function]
                _robots_used(plan, fn, bind(fn, step.args, {}, team_size), team_size)
    except RobotIndexError as exc:
        raise UserError(f"the plan does not fit this team of {team_size}: {exc.message}") from None


class Performer(Protocol):
    """What carries out a plan's skill calls: the simulated team (:class:`TeamWorld`) or a lab's own
    code (:class:`~.dispatch.DispatchWorld`)."""

    def perform_all(self, steps: Sequence[tuple[Skill, Sequence[str], Sequence[int]]]) -> list[Outcome]:
        """Carry out one tick's skill calls (skill, object names, team slots), in launch order."""

    def release(self) -> None:
        """The run is over."""

    @property
    def objects(self) -> list[dict[str, Any]]:
        """The world's objects as the run left them (AI2-THOR's metadata; [] where unknown)."""

    @property
    def layout(self) -> dict[str, Any] | None:
        """The floor for a map: ``cells`` (x, z), each member's ``start``, ``landmarks`` (id, type, x, z); None
        where the world has no positions."""


def run(plan: Plan, world: Performer, team: Sequence[Robot], *, skills: SkillSet = DEFAULT_SKILL_SET,
        max_ticks: int = DEFAULT_MAX_TICKS) -> Execution:
    """Run a checked allocated plan (see :func:`check_team`) with ``world`` carrying out its steps."""
    return _Run(plan, world, team, skills).until_done(max_ticks)


Acting = list[tuple[str, SkillCall, tuple[int, ...]]]  # one tick's (sub-task, skill call, team slots)


class _Run:
    """One run's state: the main flow, where it waits, the sub-tasks waiting for their robots and those
    working, the robots they hold, and what the run has recorded so far."""

    def __init__(self, plan: Plan, world: Performer, team: Sequence[Robot], skills: SkillSet):
        self.plan, self.world, self.team, self.skills = plan, world, team, skills
        self.team_size = len(team)
        self.trace: list[TraceEntry] = []
        self.pending: list[_Task] = []  # launched, waiting for their robots
        self.running: list[_Task] = []  # holding their robots, one step a tick
        self.claimed: set[int] = set()
        self.starts: list[tuple[str, int]] = []
        self.begin_ticks: set[int] = set()
        self.threads: dict[str, tuple[Function, Env]] = {}
        self.launched: dict[str, _Task] = {}
        self.tick = 0
        self.main = self._main_flow()
        self.waiting_for: _Task | int | None = None
        self.main_done = False

    def until_done(self, max_ticks: int) -> Execution:
        """Tick until the main flow and every sub-task it launched are done, or ``max_ticks`` have passed
        (then the execution is marked truncated)."""
        truncated = False
        self._advance_main()
        while not (self.main_done and not self.pending and not self.running):
            if self.tick >= max_ticks:
                truncated = True
                break
            self._admit()
            self._perform(self._step())
            self.tick += 1
            if isinstance(self.waiting_for, int):
                self.waiting_for -= 1
            self._advance_main()
        self.world.release()
        return Execution(
            trace=self.trace,
            transitions=max(0, len(self.begin_ticks) - 1),
            ticks=self.tick,
            starts=self.starts,
            final_objects=self.world.objects,
            truncated=truncated,
            layout=self.world.layout,
        )

    def _launch(self, fn: Function, env: Env) -> _Task:
        """Queue a sub-task; it starts working at the next tick whose robots are all free."""
        task = _Task(fn.name, _expand(self.plan, fn, env, self.team_size),
                     _robots_used(self.plan, fn, env, self.team_size))
        task.upcoming = next(task.steps, _END)
        self.pending.append(task)
        return task

    def _main_flow(self) -> Iterator[_Task | int]:
        """The plan's top level as a generator, so that it pauses where the plan waits: it yields what the
        main flow waits for, a sub-task (a direct call or a join) or a number of idle ticks (a sleep)."""
        plan, team_size = self.plan, self.team_size
        for step in plan.main:
            if isinstance(step, NewThread):
                fn = plan.by_name[step.function]
                self.threads[step.var] = (fn, bind(fn, step.args, {}, team_size))
            elif isinstance(step, Start):
                fn, env = self.threads[step.var]
                self.launched[step.var] = self._launch(fn, env)
            elif isinstance(step, Join):
                yield self.launched[step.var]
            elif isinstance(step, Call):
                fn = plan.by_name[step.function]
                yield self._launch(fn, bind(fn, step.args, {}, team_size))
            elif isinstance(step, Sleep):
                yield math.ceil(step.seconds)

    def _advance_main(self) -> None:
        """Run the main flow on until it waits for a sub-task not yet done or for idle ticks, or ends: what it
        launches in between starts together at the next tick."""
        while not self.main_done:
            if isinstance(self.waiting_for, _Task) and not self.waiting_for.done:
                return
            if isinstance(self.waiting_for, int) and self.waiting_for > 0:
                return
            try:
                self.waiting_for = next(self.main)
            except StopIteration:
                self.main_done = True

    def _admit(self) -> None:
        """Start, in launch order, each waiting sub-task whose robots no working one holds (a sub-task with no
        steps is done at once and never begins)."""
        for task in list(self.pending):
            if task.upcoming is _END:
                self.pending.remove(task)
                task.done = True
            elif not task.robots & self.claimed:
                self.claimed.update(task.robots)
                self.pending.remove(task)
                self.running.append(task)

    def _step(self) -> Acting:
        """Advance each working sub-task by one step, in launch order; one that has just taken its last step
        frees its robots (for the next tick). Returns the tick's skill calls (idle seconds make none)."""
        acting: Acting = []
        for task in list(self.running):
            step = task.advance()
            if task.upcoming is _END:
                task.done = True
                self.running.remove(task)
                self.claimed.difference_update(task.robots)
            if task.began_at is None:  # its first step: it begins working now (a transition, if the first)
                task.began_at = self.tick
                self.begin_ticks.add(self.tick)
                self.starts.append((task.name, self.tick))
            if step is not None:
                acting.append((task.name, *step))
        return acting

    def _perform(self, acting: Acting) -> None:
        """Have the world carry out the tick's calls together, and trace each with its outcome."""
        outcomes = self.world.perform_all([(self.skills[call.skill], call.objects, members)
                                           for _, call, members in acting])
        for (name, call, members), outcome in zip(acting, outcomes):
            self.trace.append(TraceEntry(
                tick=self.tick, subtask=name, robots=[self.team[m].id for m in members], skill=call.skill,
                objects=list(call.objects), action=outcome.action, object_id=outcome.object_id,
                success=outcome.success, error=outcome.error, positions=outcome.positions,
                object_position=outcome.object_position, line=call.line,
            ))
