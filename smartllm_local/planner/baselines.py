"""The paper's baseline allocations: the model's decomposition, robots chosen without the model.

- ``rule``: after Gunn and Anderson (2015), each sub-task goes to the first robot
  that has every skill it uses and can lift what it picks up, preferring one not
  busy with another sub-task of the same block; if no robot can alone, to the
  smallest team whose pooled skills and capacity suffice; if none, the task is
  refused (by the rule, not the model).
- ``random``: each sub-task goes to one robot of the team drawn at random (seeded).

Sub-tasks the decomposition launches together run in parallel while their robots
are free; a sub-task whose robots are taken starts a new block. The allocated
plan is written as text in the plan language and parsed like any other.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from itertools import combinations

import numpy as np

from ..plan_language import Plan
from ..plan_language.ir import SkillCall, Sleep
from ..robots import Robot
from .constraints.feasibility import Need, can_do
from .constraints.format import INDENT
from .decoding.protocol import REFUSAL_PREFIX

#: Chooses the team (indices into the task's team) of one sub-task, given the robots busy in its block.
Chooser = Callable[[str, Need, set[int]], "tuple[int, ...] | None"]


def rule_chooser(team: Sequence[Robot]) -> Chooser:
    """A capable robot (a free one first), else the smallest capable team (free robots first)."""
    def choose(name: str, need: Need, busy: set[int]) -> tuple[int, ...] | None:
        for size in range(1, len(team) + 1):
            capable = [c for c in combinations(range(len(team)), size) if can_do([team[i] for i in c], need)]
            if capable:
                return next((c for c in capable if not busy & set(c)), capable[0])
        return None
    return choose


def random_chooser(team: Sequence[Robot], rng: np.random.Generator) -> Chooser:
    """One robot at random for each sub-task, whatever it can do."""
    def choose(name: str, need: Need, busy: set[int]) -> tuple[int, ...]:
        return (int(rng.integers(len(team))),)
    return choose


def allocate_by(decomposed: Plan, needs: dict[str, Need], choose: Chooser) -> str:
    """The allocated plan text: the decomposition's functions with robots, launched block by block."""
    teams: dict[str, tuple[int, ...]] = {}
    blocks: list[list[str]] = []
    for group in decomposed.stages():
        block: list[str] = []
        busy: set[int] = set()
        for name in group:
            chosen = choose(name, needs[name], busy)
            if chosen is None:
                missing = ", ".join(sorted(needs[name].skills))
                return f"{REFUSAL_PREFIX}no robot or team of this one can do {name} (it needs {missing})\n"
            if busy & set(chosen):  # its robots are taken: it waits for this block to end
                blocks.append(block)
                block, busy = [], set()
            teams[name] = chosen
            block.append(name)
            busy |= set(chosen)
        if block:
            blocks.append(block)
    lines: list[str] = []
    for function in decomposed.functions:
        # A team acts together on every step; a helper a sub-task calls acts with its caller's team.
        actor = "robot_list[0]" if len(teams.get(function.name, ())) == 1 else "robot_list"
        lines.append(f"def {function.name}(robot_list):")
        for step in function.body:
            if isinstance(step, SkillCall):
                lines.append(f"{INDENT}{step.skill}({actor}, {', '.join(repr(o) for o in step.objects)})")
            elif isinstance(step, Sleep):
                lines.append(f"{INDENT}time.sleep({step.seconds:g})")
            else:
                lines.append(f"{INDENT}{step.function}(robot_list)")
        lines.append("")
    count = 0
    for block in blocks:
        first = count + 1
        for name in block:
            count += 1
            robots = ", ".join(f"robots[{i}]" for i in teams[name])
            lines.append(f"t{count} = threading.Thread(target={name}, args=([{robots}],))")
        lines += [f"t{k}.start()" for k in range(first, count + 1)]
        lines += [f"t{k}.join()" for k in range(first, count + 1)]
    return "\n".join(lines) + "\n"
