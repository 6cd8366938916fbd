"""Choosing among candidate decompositions without the benchmark's goals: each is dry-run, checked against the
goals the model itself stated, and scored.

A candidate is run in the dry-run world as the decomposition's world check runs it (one notional robot per
sub-task, with every skill, sub-tasks in the order written). Its check counts the calls that failed, the
stated conditions it meets at the end, and its idle sub-tasks: those without which it meets as many stated
conditions (a sub-task nobody asked for, or one that undoes another's work). The score weighs those, and the
model's own mean log-probability of the tokens it chose breaks ties (and alone decides where nothing else
differs, as when no goal was stated). Nothing here reads a task file: the conditions are the goal stage's.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass

from ..plan_language import Plan
from ..plan_language.ir import Call, Function, SkillCall
from ..scene import SceneObjects
from ..scoring import Condition
from ..skills import SkillSet
from .constraints.format import MAX_SUBTASKS
from .constraints.world_check import WorldCheck

SELECTORS = ("verifier", "likelihood")


@dataclass(frozen=True)
class Check:
    """What a candidate's dry run showed: its calls and those that failed, the conditions it was checked
    against and those met at the end, its sub-tasks and the idle ones among them."""

    calls: int = 0
    failed: int = 0
    goals: int = 0
    met: int = 0
    subtasks: int = 0
    idle: int = 0

    def as_dict(self) -> dict[str, int]:
        return asdict(self)


@dataclass(frozen=True)
class Weights:
    """How a check becomes a score: the share of stated conditions met, less the share of failed calls and a
    penalty per idle sub-task, plus the mean log-probability (negative, a few tenths) times ``logprob``."""

    goals: float = 1.0
    failed: float = 1.0
    idle: float = 0.25
    logprob: float = 0.1

    def as_dict(self) -> dict[str, float]:
        return asdict(self)


WEIGHTS = Weights()


def check_decomposition(plan: Plan, scene: SceneObjects, skills: SkillSet, conditions: Sequence[Condition],
                        *, idle: bool = True) -> Check:
    """Dry-run a decomposed plan and check it against ``conditions``; ``idle`` also counts the idle sub-tasks
    (a dry run more per sub-task)."""
    world = WorldCheck(scene, skills, MAX_SUBTASKS)
    start = world.run.snapshot()
    calls, failed = run_subtasks(world, plan)
    met = world.met(conditions)
    lazy = 0
    if idle and conditions:
        for k in range(len(plan.functions)):
            world.run.restore(start)
            run_subtasks(world, plan, skip=k)
            lazy += world.met(conditions) >= met
    return Check(calls=calls, failed=failed, goals=len(conditions), met=met, subtasks=len(plan.functions), idle=lazy)


def score(check: Check, mean_logprob: float, weights: Weights = WEIGHTS) -> float:
    """A candidate's score (higher is better)."""
    goals = check.met / check.goals if check.goals else 0.0
    failed = check.failed / check.calls if check.calls else 0.0
    return (weights.goals * goals - weights.failed * failed - weights.idle * check.idle
            + weights.logprob * mean_logprob)


def choose(scores: Sequence[float]) -> int:
    """The best score's candidate (the first of equals: candidate 0 is the greedy one)."""
    return max(range(len(scores)), key=lambda k: (scores[k], -k))


def run_subtasks(world: WorldCheck, plan: Plan, skip: int | None = None) -> tuple[int, int]:
    """Each sub-task's calls by a robot of its own, in order (all but ``skip``), in ``world``: calls and failures."""
    by_name = plan.by_name
    calls = failed = 0
    for k, function in enumerate(plan.functions):
        if k == skip:
            continue
        for step in _steps(function, by_name, set()):
            calls += 1
            failed += not world.perform([(None, step.skill, step.objects)], [k])
    return calls, failed


def _steps(function: Function, by_name: Mapping[str, Function], seen: set[str]) -> list[SkillCall]:
    """A function's skill calls, the helpers it calls written inline (each helper once on a path: no recursion)."""
    steps: list[SkillCall] = []
    for step in function.body:
        if isinstance(step, SkillCall):
            steps.append(step)
        elif isinstance(step, Call) and step.function in by_name and step.function not in seen:
            steps.extend(_steps(by_name[step.function], by_name, seen | {function.name}))
    return steps

