"""An allocated plan every call of which succeeds when the team runs it: Exe 1.00 by construction.

The stages check each call as it is written, against worlds close to the team's but not the same: the
decomposition's dry run gives each sub-task a notional robot of its own, and the allocation meets a dead end where
no robot list of the team runs a sub-task from the state the earlier ones leave (the 0.5B switched a stove knob on
twice; the second time the knob nearest the robot was the one already on). So the allocated plan is run once more
in process, exactly as the executor runs it (the world's own rules, the team's robots, threads interleaved a step a
tick), and where a call fails the planner changes the plan before anyone executes it:

- a block of threads in which the call failed runs its threads one after the other (each joined before the next
  starts), where that fails fewer calls: where no other robot can take a thread, threads run in turn;
- otherwise the call is taken out, with the comments right above it. A call that fails changes nothing, so the
  world ends as it did; a sub-task left with no call goes, with its lines in the orchestration.

Repeated until every call succeeds (each round removes a line or orders a block, so it ends); each change is
recorded. Only the plan, the scene and the team are read.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from ..errors import PlanError
from ..executor import Execution, TraceEntry
from ..plan_language import Call, Function, Join, NewThread, Plan, SkillCall, Start, parse_plan
from ..plan_language.ir import MainStep
from ..robots import Robot
from ..scene import SceneObjects
from ..skills import SkillSet
from .idle_steps import comments_above, definition_lines

#: Who refused, where no call of a plan succeeds.
WORLD_CHECK = "world check"

RunPlan = Callable[[Plan], Execution]
ParsePlan = Callable[[str], Plan]


@dataclass
class Executable:
    """The plan as the team will run it, its text, and what was changed to get there (none: as allocated)."""

    text: str
    plan: Plan
    changes: list[str]
    refusal: str | None = None  # no call of the plan succeeds: nothing of it is left to run


def for_team(text: str, plan: Plan, scene: SceneObjects, team: Sequence[Robot], skills: SkillSet) -> Executable:
    """:func:`make_executable` with the scene's world running the plan in process with ``team``."""
    return make_executable(
        text, plan,
        run=lambda p: scene.world.run_in_process(p, scene.floor_plan, team, skills),
        parse=lambda t: parse_plan(t, form="allocated", skills=skills, team_size=len(team), scene_types=scene.types,
                                   name="<allocation output>"))


def make_executable(text: str, plan: Plan, run: RunPlan, parse: ParsePlan) -> Executable:
    """``plan`` (allocated, from ``text``), changed until ``run`` (the executor's run, in process) fails no call."""
    changes: list[str] = []
    execution = run(plan)
    while True:
        failed = [e for e in execution.trace if not e.success]
        if not failed:
            return Executable(text, plan, changes)
        entry = failed[0]
        block = _block_of(plan, entry.subtask)
        if block:
            trial_text = _in_turn(text, block)
            trial = _parsed(parse, trial_text)
            tried = run(trial) if trial is not None else None
            if tried is not None and sum(not e.success for e in tried.trace) < len(failed):
                changes.append(f"threads of {', '.join(t.function for t in block)} run one after the other: "
                               f"{_call_text(entry)} failed with them at once")
                text, plan, execution = trial_text, trial, tried
                continue
        shorter = _without(text, plan, entry.line)
        parsed = _parsed(parse, shorter) if shorter is not None else None
        if parsed is None:
            if shorter is None or _defines(shorter):
                return Executable(text, plan, changes)  # not reached: each call the run traces is a line of a body
            return Executable(text, plan, changes, "no call of the plan succeeds with this team "
                                                   f"({_call_text(entry)}: {entry.error or 'failed'})")
        changes.append(f"taken out: {_call_text(entry)} ({entry.error or 'failed'})")
        text, plan = shorter, parsed
        execution = run(plan)


def _defines(text: str) -> bool:
    """Whether the text defines a function (taking calls out can leave none)."""
    return any(line.startswith("def ") for line in text.splitlines())


def _parsed(parse: ParsePlan, text: str) -> Plan | None:
    """The plan of ``text``; None where it is not one (a plan with no sub-task left)."""
    try:
        return parse(text)
    except PlanError:
        return None


def _call_text(entry: TraceEntry) -> str:
    objects = ", ".join(repr(o) for o in entry.objects)
    return f"{entry.skill}({objects}) in {entry.subtask}"


@dataclass
class _Thread:
    """A thread the orchestration starts: its function, the 0-based lines of its start and of its join."""

    function: str
    start: int
    join: int | None = None


def _blocks(plan: Plan) -> list[list[_Thread]]:
    """The threads started together, block by block (a join, a direct call or a sleep ends a block)."""
    targets: dict[str, str] = {}
    unjoined: dict[str, _Thread] = {}
    blocks: list[list[_Thread]] = [[]]
    for step in plan.main:
        if isinstance(step, NewThread):
            targets[step.var] = step.function
        elif isinstance(step, Start):
            unjoined[step.var] = thread = _Thread(targets[step.var], step.line - 1)
            blocks[-1].append(thread)
        else:
            if blocks[-1]:
                blocks.append([])
            if isinstance(step, Join) and step.var in unjoined:
                unjoined.pop(step.var).join = step.line - 1
    return [b for b in blocks if b]


def _block_of(plan: Plan, function: str) -> list[_Thread]:
    """The first block of two threads or more that starts ``function`` (none: it runs alone)."""
    return next((b for b in _blocks(plan) if len(b) > 1 and any(t.function == function for t in b)), [])


def _in_turn(text: str, block: Sequence[_Thread]) -> str:
    """The text with each thread of ``block`` joined right after it starts (its later join gone)."""
    lines = text.splitlines(keepends=True)
    joins = {t.start: t.join for t in block if t.join is not None}
    out = []
    for n, line in enumerate(lines):
        if n not in joins.values():
            out.append(line)
        if n in joins:
            out.append(lines[joins[n]])  # type: ignore[index]
    return "".join(out)


def _without(text: str, plan: Plan, line: int) -> str | None:
    """The text without the call at ``line`` and the comments right above it; where that leaves its function no
    call, without the function and every line that launches, joins or calls it (and so on, for a function that
    only called it). None where no call is at ``line``."""
    lines = text.splitlines(keepends=True)
    body = {s.line: f for f in plan.functions for s in f.body}
    if line not in body:
        return None
    dropped = {line - 1}
    emptied = [body[line]] if _calls(body[line], dropped) == 0 else []
    while emptied:
        function = emptied.pop()
        dropped |= definition_lines(lines, function.line - 1)
        dropped |= {s.line - 1 for s in _launching(plan, function.name)}
        for caller in plan.functions:
            calling = {s.line - 1 for s in caller.body if isinstance(s, Call) and s.function == function.name}
            if calling and caller.line - 1 not in dropped:
                dropped |= calling
                if _calls(caller, dropped) == 0:
                    emptied.append(caller)
    dropped |= comments_above(lines, dropped)
    return "".join(text_line for n, text_line in enumerate(lines) if n not in dropped)


def _launching(plan: Plan, function: str) -> list[MainStep]:
    """The orchestration's lines that launch, start or join ``function`` (a thread's variable may be used again
    for another function)."""
    targets: dict[str, str] = {}
    steps: list[MainStep] = []
    for step in plan.main:
        if isinstance(step, NewThread):
            targets[step.var] = step.function
        if isinstance(step, (NewThread, Call)) and step.function == function or \
                isinstance(step, (Start, Join)) and targets.get(step.var) == function:
            steps.append(step)
    return steps


def _calls(function: Function, dropped: set[int]) -> int:
    """The function's skill and function calls left where the 0-based lines ``dropped`` go."""
    return sum(isinstance(s, (SkillCall, Call)) and s.line - 1 not in dropped for s in function.body)
