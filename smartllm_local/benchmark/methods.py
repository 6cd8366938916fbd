"""Planning methods as plug-ins: SMART-LLM, the paper's baselines, and the reference plans.

A method is a list of steps (:class:`~..planner.steps.Step`), each of which adds one StageRecord, under its
stage's name, to a task's PlanResult; SMART-LLM's are the planner's own (:meth:`Planner.steps`), which the
``plan`` command runs too. The benchmark runner takes every task through one step before the next (so a model
keeps each stage's examples in its cache), except that a step which goes on in its predecessor's context runs
right after it for each task, always through :func:`~..planner.steps.run_steps`. It saves each finished
stage, and never needs to know which method it runs: a new method is a new class here, not a branch in the
runner.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from pathlib import Path
from typing import Protocol

from ..errors import UserError
from ..goal_language import condition_line, parse_goal_statement, statement_of
from ..plan_language import Plan, parse_plan
from ..planner.baselines import allocate_by, random_chooser, rule_chooser
from ..planner.constraints.feasibility import function_needs
from ..planner.constraints.goal import goal_vocabulary
from ..planner.goal_stage import checked_against_team, holders_asked
from ..planner.pipeline import Planner
from ..planner.progress import SILENT
from ..planner.readings import may_place, merge, placements, unsettled
from ..planner.result import PlanResult, StageRecord
from ..planner.steps import Step
from ..robots import Catalogue
from ..scoring import Condition
from ..worlds import Ai2ThorWorld, World
from .reference_plans import default_plans_dir
from .tasks import Task

DEFAULT_TIME_LIMIT = 60.0  # seconds of search per task for the goal-planner (the household tasks need far less)


class Method(Protocol):
    name: str

    def steps(self, task: Task) -> Sequence[Step]:
        """The steps that plan ``task``, in order (the same stages, by name, for every task of a run)."""
        ...


class SmartLLM:
    """SMART-LLM's three stages on the model: decomposition, coalition formation, allocation (the planner's
    steps, as its configuration has them)."""

    name = "smartllm"

    def __init__(self, planner: Planner, catalogue: Catalogue):
        self.planner, self.catalogue = planner, catalogue

    def steps(self, task: Task) -> list[Step]:
        return self.planner.steps()


class DecompositionThenRule:
    """The model's decomposition (the planner's step); robots by a rule (``decomp-rule``) or at random
    (``decomp-random``)."""

    def __init__(self, planner: Planner, catalogue: Catalogue, rule: str):
        self.planner, self.catalogue, self.rule = planner, catalogue, rule
        self.name = f"decomp-{rule}"

    def steps(self, task: Task) -> list[Step]:
        return [Step("decomposition", self.planner.decompose), Step("allocation", self.allocate)]

    def allocate(self, result: PlanResult) -> None:
        started = time.perf_counter()
        team = self.catalogue.team(result.robots)
        scene = self.planner.scene(result.floor_plan)
        decomposed = result.stage("decomposition").plan
        choose = rule_chooser(team) if self.rule == "rule" else \
            random_chooser(team, self.planner.stage_rng(result, "allocation"))
        needs = function_needs(decomposed, scene, self.catalogue.skills.lifting)  # type: ignore[arg-type]
        record = StageRecord("allocation", output=allocate_by(decomposed, needs, choose))  # type: ignore[arg-type]
        record.seconds = time.perf_counter() - started
        record.plan = parse_plan(record.output, form="allocated", skills=self.catalogue.skills, team_size=len(team),
                                 scene_types=scene.types, name=f"<{self.name} allocation>")
        if record.plan.is_refusal:
            record.refusal, record.refused_by = record.plan.refusal, "rule"
            result.refusal = record.refusal
        result.add(record)


class GoalPlanner:
    """The goal stage states the goal; Fast Downward finds the steps for the team (``goal-planner``).

    With ``read_steps`` (the default), the model also decomposes the task (SMART-LLM's decomposition, checked in
    the world as it is written), and where the decomposition puts a thing the instruction names into a holder it
    names, the planner's goal has it there, whatever the statement said (:mod:`~..planner.readings`).

    With ``oracle``, the task's own goal conditions are the goal and no model runs
    (``goal-planner-oracle``): it measures the planner alone, what it reaches when the goal is right.
    ``world``: the world the tasks are in (none given: the planner's, else AI2-THOR's), whose kind picks the
    planning model (:func:`~smartllm_local.planner.classical.planning.goal_planning`).
    """

    def __init__(self, planner: Planner | None, catalogue: Catalogue, *, time_limit: float, oracle: bool = False,
                 world: World | None = None, read_steps: bool = True):
        self.planner, self.catalogue, self.time_limit, self.oracle = planner, catalogue, time_limit, oracle
        self.read_steps = read_steps and not oracle
        self.world = world or (planner.world if planner is not None else Ai2ThorWorld())
        self.name = "goal-planner-oracle" if oracle else "goal-planner"

    def steps(self, task: Task) -> list[Step]:
        search = Step("allocation", lambda result: self.allocate(task, result))
        if self.oracle:
            return [search]
        steps = [Step("decomposition", self.decompose)] if self.reads_steps(task) else []
        return [Step("goal", self.state_goals), *steps, search]

    def reads_steps(self, task: Task) -> bool:
        """Whether the task's decomposition is read: with ``read_steps``, where its scene has holders to put things
        in (a site's goals are states alone, so its steps could say nothing the statement does not)."""
        return self.read_steps and any(goal_vocabulary(self.world.scene(task.floor_plan)).holders.values())

    def state_goals(self, result: PlanResult) -> None:
        assert self.planner is not None
        stated = self.planner.goals(result.instruction, result.floor_plan)
        result.add(stated.record)
        if stated.refusal is not None:
            result.refusal = stated.refusal
        elif stated.error:
            result.error = stated.error

    def decompose(self, result: PlanResult) -> None:
        """The decomposition to read, where the instruction names a holder of the scene: the steps are read only
        for holders it names (:func:`~..planner.readings.may_place`), so elsewhere none is written (the stage
        adds no record; a run's tasks keep the same steps)."""
        if may_place(result.instruction, self.world.scene(result.floor_plan)):
            assert self.planner is not None
            self.planner.decompose(result)

    def allocate(self, task: Task, result: PlanResult) -> None:
        from ..planner.classical.planning import plan_to_goal  # Unified Planning loads only for this method

        team, scene = self.catalogue.team(task.robots), self.world.scene(result.floor_plan)
        if self.oracle:
            conditions = statement_of(task.goals).conditions
        else:  # less goals out of reach that nobody asked for, as SMART-LLM's goal check leaves them
            goal = result.stage("goal")
            stated = parse_goal_statement(goal.output, where="<goal output>").conditions
            kept = checked_against_team(goal, result.instruction, scene, stated, team, self.catalogue.skills)
            conditions = [c for c in stated if c in kept]
        placed = unsettled(self._placements(result), conditions, holders_asked(result.instruction, scene)) \
            if self.reads_steps(task) else []
        if placed:
            conditions = merge(conditions, placed)
        progress = self.planner.progress if self.planner is not None else SILENT
        progress.stage_started("allocation", 0)  # a search, which a plan's display shows as a stage too
        record = plan_to_goal(conditions, task.floor_plan, team, self.catalogue.skills,
                              time_limit=self.time_limit, name=task.id, world=self.world)
        record.placements = [condition_line(c) for c in placed]
        progress.stage_ended(record)
        result.add(record)
        if record.refusal is not None:
            result.refusal = record.refusal
        elif record.error:
            result.error = record.error

    def _placements(self, result: PlanResult) -> list[Condition]:
        """Where the task's decomposition (if one was written) puts the things its instruction names."""
        record = result.stages.get("decomposition")
        plan = record.plan if record is not None else None
        if not isinstance(plan, Plan) or plan.is_refusal:
            return []
        return placements(plan, self.world.scene(result.floor_plan), self.catalogue.skills, result.instruction)


class Reference:
    """The benchmark's hand-written reference plans: the ceiling, and proof that the harness is sound."""

    name = "reference"

    def __init__(self, catalogue: Catalogue, plans_dir: Path | None = None):
        self.catalogue = catalogue
        self.plans_dir = plans_dir or default_plans_dir()

    def steps(self, task: Task) -> list[Step]:
        return [Step("allocation", lambda result: self.allocate(task, result))]

    def allocate(self, task: Task, result: PlanResult) -> None:
        path = self.plans_dir / f"{task.id}.py"
        if not task.feasible:
            why = f"the team lacks {', '.join(task.missing_skills)}" if task.missing_skills else \
                "the team cannot meet a goal condition"
            text = f"# INFEASIBLE: {why}\n"
        elif path.is_file():
            text = path.read_text(encoding="utf-8")
        else:
            raise UserError(f"task {task.id} has no reference plan ({path} does not exist)")
        record = StageRecord("allocation", output=text)
        record.plan = parse_plan(text, form="allocated", skills=self.catalogue.skills, team_size=len(task.robots),
                                 name=str(path))
        if record.plan.is_refusal:
            record.refusal, record.refused_by = record.plan.refusal, "rule"
            result.refusal = record.refusal
        result.add(record)


METHODS = ("smartllm", "decomp-random", "decomp-rule", "goal-planner", "goal-planner-oracle", "reference")
#: The methods that run no model.
MODEL_FREE = frozenset({"reference", "goal-planner-oracle"})


def check_time_limit(planner_time_limit: float) -> None:
    """The goal-planner's search time per task must be a positive number of seconds.

    Raises:
        UserError: it is not.
    """
    if not planner_time_limit > 0:
        raise UserError(f"--planner-time-limit must be a positive number of seconds, not {planner_time_limit:g}")


def make_method(name: str, catalogue: Catalogue, planner: Planner | None, plans_dir: Path | None = None, *,
                planner_time_limit: float = DEFAULT_TIME_LIMIT, world: World | None = None,
                read_steps: bool = True) -> Method:
    """The method ``name`` (the reference plans, from ``plans_dir`` or the benchmark's, and the goal-planner
    on the task's own goals need no model); ``planner_time_limit``: the goal-planner's search, per task, in
    ``world`` (the tasks' world: see :class:`GoalPlanner`)."""
    if name == "reference":
        return Reference(catalogue, plans_dir)
    if name not in METHODS:
        raise UserError(f"--method must be one of {', '.join(METHODS)}, not {name!r}")
    if name.startswith("goal-planner"):
        check_time_limit(planner_time_limit)
        return GoalPlanner(planner, catalogue, time_limit=planner_time_limit, oracle=name == "goal-planner-oracle",
                           world=world, read_steps=read_steps)
    assert planner is not None
    if name == "smartllm":
        return SmartLLM(planner, catalogue)
    return DecompositionThenRule(planner, catalogue, name.removeprefix("decomp-"))
