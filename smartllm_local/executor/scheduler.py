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

    def as_dict(self) -> dict[str, Any]:
        """The entry as ``execute --trace`` writes it, with AI2-THOR's names for the action's fields."""
        return {"tick": self.tick, "subtask": self.subtask, "robots": list(self.robots), "skill": self.skill,
                "objects": list(self.objects), "action": self.action, "objectId": self.object_id,
                "success": self.success, "errorMessage": self.error}


@dataclass
class Execution:
    """What a run did: its trace, its structure, and the world's final objects."""

    trace: list[TraceEntry]
    transitions: int
    ticks: int
    starts: list[tuple[str, int]]  # (sub-task, tick it began working)
    final_objects: list[dict[str, Any]] = field(repr=False)
    truncated: bool = False

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


class World(Protocol):
    """What carries out a plan's skill calls: the simulated team (:class:`TeamWorld`) or a lab's own
    code (:class:`~.dispatch.DispatchWorld`)."""

    def perform_all(self, steps: Sequence[tuple[Skill, Sequence[str], Sequence[int]]]) -> list[Outcome]:
        """Carry out one tick's skill calls (skill, object names, team slots), in launch order."""

    def release(self) -> None:
        """The run is over."""

    @property
    def objects(self) -> list[dict[str, Any]]:
        """The world's objects as the run left them (AI2-THOR's metadata; [] where unknown)."""


def run(plan: Plan, world: World, team: Sequence[Robot], *, skills: SkillSet = DEFAULT_SKILL_SET,
        max_ticks: int = DEFAULT_MAX_TICKS) -> Execution:
    """Run a checked allocated plan (see :func:`check_team`) with ``world`` carrying out its steps."""
    team_size = len(team)
    trace: list[TraceEntry] = []
    pending: list[_Task] = []
    running: list[_Task] = []
    claimed: set[int] = set()
    starts: list[tuple[str, int]] = []
    begin_ticks: set[int] = set()
    threads: dict[str, tuple[Function, Env]] = {}
    launched: dict[str, _Task] = {}

    def launch(fn: Function, env: Env) -> _Task:
        task = _Task(fn.name, _expand(plan, fn, env, team_size), _robots_used(plan, fn, env, team_size))
        task.upcoming = next(task.steps, _END)
        pending.append(task)
        return task

    def main_flow() -> Iterator[_Task | int]:
        """Yields what the main flow waits for: a task, or a number of idle ticks."""
        for step in plan.main:
            if isinstance(step, NewThread):
                fn = plan.by_name[step.function]
                threads[step.var] = (fn, bind(fn, step.args, {}, team_size))
            elif isinstance(step, Start):
                fn, env = threads[step.var]
                launched[step.var] = launch(fn, env)
            elif isinstance(step, Join):
                yield launched[step.var]
            elif isinstance(step, Call):
                fn = plan.by_name[step.function]
                yield launch(fn, bind(fn, step.args, {}, team_size))
            elif isinstance(step, Sleep):
                yield math.ceil(step.seconds)

    tick = 0
    main = main_flow()
    waiting_for: _Task | int | None = None
    main_done = False
    truncated = False

    def advance_main() -> None:
        nonlocal waiting_for, main_done
        while not main_done:
            if isinstance(waiting_for, _Task) and not waiting_for.done:
                return
            if isinstance(waiting_for, int) and waiting_for > 0:
                return
            try:
                waiting_for = next(main)
            except StopIteration:
                main_done = True

    advance_main()
    while not (main_done and not pending and not running):
        if tick >= max_ticks:
            truncated = True
            break
        for task in list(pending):
            if task.upcoming is _END:
                pending.remove(task)
                task.done = True
            elif not task.robots & claimed:
                claimed.update(task.robots)
                pending.remove(task)
                running.append(task)
        acting: list[tuple[str, SkillCall, tuple[int, ...]]] = []
        for task in list(running):
            step = task.advance()
            if task.upcoming is _END:
                task.done = True
                running.remove(task)
                claimed.difference_update(task.robots)
            if task.began_at is None:
                task.began_at = tick
                begin_ticks.add(tick)
                starts.append((task.name, tick))
            if step is not None:
                acting.append((task.name, *step))
        outcomes = world.perform_all([(skills[call.skill], call.objects, members) for _, call, members in acting])
        for (name, call, members), outcome in zip(acting, outcomes):
            trace.append(TraceEntry(
                tick=tick, subtask=name, robots=[team[m].id for m in members], skill=call.skill,
                objects=list(call.objects), action=outcome.action, object_id=outcome.object_id,
                success=outcome.success, error=outcome.error,
            ))
        tick += 1
        if isinstance(waiting_for, int):
            waiting_for -= 1
        advance_main()
    world.release()
    return Execution(
        trace=trace,
        transitions=max(0, len(begin_ticks) - 1),
        ticks=tick,
        starts=starts,
        final_objects=world.objects,
        truncated=truncated,
    )
