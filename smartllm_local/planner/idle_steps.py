"""Steps that change nothing, taken out of a decomposition before the teams are formed.

A model writes steps in a sub-task that the same sub-task undoes: asked for a coffee and the apple in the fridge,
the 1.5B opened the fridge in the coffee's sub-task, went to it again and closed it, with nothing put in. Harmless
to the goals, but the coalition and the allocation take every step as a need: the coffee's sub-task then needed a
robot that opens fridges besides the one that switches the coffee machine on, both robots went to it, and the
apple's sub-task, which needs the fridge's robot, waited for it (a transition the reference plan does not make:
RU 0, by the paper's definition of it, for a plan that met every goal).

So a pair of steps where the later one undoes the earlier (open and close, switch on and off the same object), in
one sub-task or two, with the GoToObject steps that led to each and the comments right above them, is taken out
where the dry run shows it was idle: run as the decomposition's world check runs it (a notional robot per sub-task,
in the order written), no other call fails that did not and the world ends in the same state, every object as it
was (where the robots stand aside). A switch on and off that filled or cooked something in between changes the end,
and stays; so does an open and close with something put in between (the put fails without it). Across sub-tasks:
asked to throw the plunger out and switch the light off, the 1.5B switched the light off in one sub-task and on
again in the next, and the planner's last sub-task switched it off once more; the two later switches go, and the
sub-task left with no action goes whole (its definition and its thread), where another still acts. Only the
model's plan and the planner's lines in it are read.
"""

from __future__ import annotations

import json
import re
from collections.abc import Collection, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

from ..scene import SceneObjects
from ..scoring import as_scored
from ..skills import SkillSet
from .constraints.format import INDENT, MAX_SUBTASKS
from .constraints.world_check import WorldCheck
from .constraints.written import CALL_LINE

#: Each AI2-THOR action that a later one in the same sub-task undoes, and that one.
UNDONE_BY = {"OpenObject": "CloseObject", "ToggleObjectOn": "ToggleObjectOff"}


#: An orchestration line that makes a thread: its variable and its target.
THREAD = re.compile(r"^(\w+) = threading\.Thread\(target=(\w+)\)$")
#: An object's fields that say where the robots stand, not what state the world is in (a sub-task's robot is its
#: own: no other sub-task starts where it ended).
WHERE_ROBOTS_STAND = frozenset({"distance", "visible", "isInteractable"})


@dataclass(frozen=True)
class Step:
    """A skill call of a decomposition's text: its line, its function (by order written), skill and objects."""

    line: int  # its index among the text's lines
    function: int
    skill: str
    objects: tuple[str, ...]


def drop_idle_steps(text: str, scene: SceneObjects, skills: SkillSet) -> tuple[str, list[str]]:
    """The decomposition without its idle pairs of steps (and the GoToObject steps and comments that served
    them; a sub-task left with no action, whole), and the lines taken out (none: the text as it was). A text with
    a line this does not know (a helper call) is left as it is."""
    lines = text.splitlines(keepends=True)
    steps = skill_steps(lines, skills)
    if steps is None:
        return text, []
    actions = {name: s.action for name, s in skills.items()}
    pairs = [(first, second) for a, first in enumerate(steps) for second in steps[a + 1:]
             if _undoes(first, second, actions)]
    if not pairs:
        return text, []
    base = dry_outcome(steps, set(), scene, skills)
    dropped: set[int] = set()
    gone: set[int] = set()  # sub-tasks the pairs left with no action
    for first, second in pairs:
        pair = {first.line, second.line}
        if pair & dropped:
            continue
        for trial in (pair | gotos_before(steps, pair, actions), pair):
            taken = dropped | trial
            emptied = {f for f in (first.function, second.function) if not acts(steps, f, taken, actions)}
            if emptied and not any(acts(steps, s.function, taken, actions) for s in steps):
                continue  # the plan keeps a sub-task
            taken |= {s.line for s in steps if s.function in emptied}
            if _same(base, dry_outcome(steps, taken, scene, skills)):
                dropped, gone = taken, gone | emptied
                break
    if not dropped:
        return text, []
    dropped |= sleeps_after(lines, steps, dropped, actions)
    dropped |= comments_above(lines, dropped)
    for function in gone:
        dropped |= function_lines(lines, function)
    return "".join(line for n, line in enumerate(lines) if n not in dropped), [lines[n] for n in sorted(dropped)]


def skill_steps(lines: Sequence[str], skills: SkillSet) -> list[Step] | None:
    """The skill calls of each function's body, in order; None where a body holds a line other than a comment,
    a sleep or a skill call."""
    steps: list[Step] = []
    function = -1
    for n, line in enumerate(lines):
        if line.startswith("def "):
            function += 1
            continue
        if function < 0 or not line.startswith(INDENT):
            continue
        body = line.strip()
        if body.startswith("#") or body.startswith("time.sleep("):
            continue
        match = CALL_LINE.match(line.rstrip("\n"))
        if match is None or match.group(1) not in skills:
            return None
        steps.append(Step(n, function, match.group(1), tuple(o for o in match.group(3, 4) if o is not None)))
    return steps


def _undoes(first: Step, second: Step, actions: dict[str, str]) -> bool:
    undoing = UNDONE_BY.get(actions[first.skill])
    return undoing is not None and actions[second.skill] == undoing and first.objects[:1] == second.objects[:1]


def gotos_before(steps: Sequence[Step], pair: Collection[int], actions: dict[str, str]) -> set[int]:
    """The GoToObject steps right before each step of the pair (in its function): they led there."""
    gotos = set()
    for before, step in zip(steps, steps[1:]):
        if step.line in pair and before.function == step.function and actions[before.skill] == "":
            gotos.add(before.line)
    return gotos


def acts(steps: Sequence[Step], function: int, dropped: Collection[int], actions: dict[str, str]) -> bool:
    """Whether the function keeps an action (a body of GoToObject steps alone is not a sub-task)."""
    return any(s.function == function and s.line not in dropped and actions[s.skill] for s in steps)


def dry_run(steps: Sequence[Step], dropped: Collection[int], scene: SceneObjects,
            skills: SkillSet) -> tuple[set[int], WorldCheck]:
    """The lines whose calls fail, with ``dropped`` left out, and the world they leave (a notional robot per
    function, in the order written, as the decomposition's world check runs them)."""
    world = WorldCheck(scene, skills, MAX_SUBTASKS)
    failed = {s.line for s in steps if s.line not in dropped
              and not world.perform([(None, s.skill, s.objects)], [min(s.function, MAX_SUBTASKS - 1)])}
    return failed, world


def outcomes(world: WorldCheck, steps: Sequence[Step]) -> Iterator[tuple[Step, Any]]:
    """Each step with the outcome of performing it in ``world`` (a notional robot per function, in the order
    written), as the executor's TeamWorld gives it: the holder an opening opened is its ``object_id``."""
    for step in steps:
        yield step, world.run.apply([min(step.function, MAX_SUBTASKS - 1)], step.skill, step.objects)


def dry_outcome(steps: Sequence[Step], dropped: Collection[int], scene: SceneObjects,
                skills: SkillSet, *, alike: bool = False) -> tuple[set[int], str]:
    """The lines whose calls fail, and the world's end state, with ``dropped`` left out (``alike``: as the goals see
    it, :func:`~smartllm_local.scoring.as_scored`)."""
    failed, world = dry_run(steps, dropped, scene, skills)
    if alike:
        return failed, json.dumps(as_scored(world.objects()))
    objects = [{k: _rounded(v) for k, v in o.items() if k not in WHERE_ROBOTS_STAND} for o in world.objects()]
    return failed, json.dumps(objects, sort_keys=True, default=str)


def text_outcome(lines: Sequence[str], scene: SceneObjects, skills: SkillSet) -> tuple[set[int], str] | None:
    """:func:`dry_outcome` of a decomposition's text, its end as the goals see it (None: a text of other lines)."""
    steps = skill_steps(lines, skills)
    return None if steps is None else dry_outcome(steps, (), scene, skills, alike=True)


def ends_as(base: tuple[set[int], str] | None, after: Sequence[str], scene: SceneObjects, skills: SkillSet) -> bool:
    """Whether the text ``after`` fails no more calls in the dry run than the text whose :func:`text_outcome` is
    ``base`` and leaves the world alike (its lines are others, so the failures are counted)."""
    new = None if base is None else text_outcome(after, scene, skills)
    return new is not None and len(new[0]) <= len(base[0]) and new[1] == base[1]


def _rounded(value: object) -> object:
    """The value with its numbers to the micrometre: a box moved by the same steps in another order differs in the
    last bits (-3.3630784153938293 and -3.36307841539383), and the end is the same."""
    if isinstance(value, float):
        return round(value, 6) + 0.0  # (no -0.0)
    if isinstance(value, dict):
        return {k: _rounded(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_rounded(v) for v in value]
    return value


def _same(base: tuple[set[int], str], trial: tuple[set[int], str]) -> bool:
    return trial[0] <= base[0] and trial[1] == base[1]


def sleeps_after(lines: Sequence[str], steps: Sequence[Step], dropped: Collection[int],
                  actions: dict[str, str]) -> set[int]:
    """The sleeps right after a dropped switch-on (comments aside): they waited for it."""
    sleeps = set()
    for step in steps:
        if step.line in dropped and actions[step.skill] == "ToggleObjectOn":
            k = step.line + 1
            while k < len(lines) and lines[k].strip().startswith("#"):
                k += 1
            if k < len(lines) and lines[k].strip().startswith("time.sleep("):
                sleeps.add(k)
    return sleeps


def function_name(header: str) -> str:
    """The name a ``def`` line defines."""
    return header[len("def "):header.index("(")]


def body_end(lines: Sequence[str], header: int) -> int:
    """The index of the first line after the body of the function defined at ``header``."""
    end = header + 1
    while end < len(lines) and lines[end].startswith(INDENT):
        end += 1
    return end


def definition_lines(lines: Sequence[str], header: int) -> set[int]:
    """The lines of the function defined at ``header``: the header, its body and the blank line after it."""
    end = body_end(lines, header)
    return set(range(header, end + (end < len(lines) and not lines[end].strip())))


def comments_above(lines: Sequence[str], dropped: Collection[int]) -> set[int]:
    """The comment lines right above a dropped line (they said what it would do)."""
    comments = set()
    for n in dropped:
        k = n - 1
        while k >= 0 and lines[k].startswith(INDENT) and lines[k].strip().startswith("#"):
            comments.add(k)
            k -= 1
    return comments


def function_lines(lines: Sequence[str], function: int) -> set[int]:
    """The lines of the ``function``-th definition (its header, its body and the blank line after it) and of the
    orchestration that runs it (its call, or its thread's creation, start and join)."""
    defs = [n for n, line in enumerate(lines) if line.startswith("def ")]
    header = defs[function]
    name, taken = function_name(lines[header]), definition_lines(lines, header)
    thread = None
    for n, line in enumerate(lines):
        line = line.rstrip("\n")
        if line == f"{name}()":
            taken.add(n)
        elif (made := THREAD.match(line)) is not None and (made.group(2) == name or made.group(1) == thread):
            thread = made.group(1) if made.group(2) == name else None
            taken |= {n} if thread else set()
        elif thread is not None and line in (f"{thread}.start()", f"{thread}.join()"):
            taken.add(n)
    return taken
