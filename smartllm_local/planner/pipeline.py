"""SMART-LLM's three stages on a local model: decomposition, coalition formation, allocation.

Each stage is a plain method of one argument, the task's result, and :meth:`Planner.steps` lists them as
this planner's configuration has them: :func:`.steps.run_steps` takes a task through them, for the ``plan``
command, and a benchmark run takes every task through one stage before the next (the examples at the head of
a stage's prompt then stay in the model's cache from one task to the next). Coalition and allocation share a
prompt where the model's context holds it: a task's allocation goes on in the context its coalition left,
right after it.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import PlanError, UserError
from ..files import json_text, write_atomic
from ..plan_language import Plan, parse_plan
from ..robots import Catalogue, Robot
from ..scene import SceneObjects
from ..skills import SkillSet
from ..worlds import Ai2ThorWorld, World
from .backends.base import Backend
from .candidates import Candidates, mean_logprob, write_all
from .constraints.coalition import LINE as COALITION_LINE
from .constraints.coalition import CoalitionConstraint, chosen_teams
from .constraints.feasibility import function_needs
from .constraints.finish import Said
from .constraints.format import MAX_SUBTASKS
from .constraints.plan import PlanConstraint
from .constraints.repair import Repairer
from .constraints.restated import RestatedAllocation, restated_bodies
from .constraints.world_check import WorldCheck, for_decomposition
from .decoding.protocol import REFUSAL_PREFIX, Constraint
from .decoding.sampling import Sampling
from .decoding.writer import exact_budget
from .errands import drop_errands
from .executable import WORLD_CHECK, for_team
from .finish_fold import fold_finish
from .goal_stage import GOAL_CHECK, StatedGoals, checked_against_team, said_of, state_goals, stated_conditions
from .idle_steps import drop_idle_steps
from .in_turn import free_blocks, started_together
from .joined import join_in_turn
from .kept_in_hand import put_kept_things
from .opened_for_nothing import drop_opened_for_nothing
from .opening_moved import move_openings
from .progress import SILENT, StageProgress
from .prompting.asked_words import load_state_words
from .prompting.chat import chat_format, prompt_tokens
from .prompting.prompts import (
    ALLOCATION_GLUE,
    Example,
    Prompt,
    PromptOptions,
    allocation_prompt,
    coalition_prompt,
    decomposition_prompt,
    examples_for,
    load_examples,
)
from .result import PlanResult, StageRecord
from .stages import Fitted, check_output, fit_prompt, run_stage, spelled_cost
from .steps import Step, run_steps
from .verifier import check_decomposition, choose, score

DEFAULT_BUDGETS = {"decomposition": 1024, "coalition": 896, "allocation": 1280}
#: Room for a task's own part of the coalition prompt (its plan, team and objects: 325-630 tokens on average, measured).
OWN_PART = 768


def allocation_budget(decomposition: StageRecord, functions: int, ceiling: int) -> int:
    """The allocated plan restates the decomposed one with robots, plus a thread, start and join per
    function: twice its tokens and 64 a function is ample, and the tighter budget leaves room for
    more examples in a 4,096-token context."""
    written = decomposition.generated_tokens + decomposition.forced_tokens
    return min(ceiling, 2 * written + 64 * functions + 128)


_COALITION_LINE = re.compile(rf"{COALITION_LINE.pattern}|^# INFEASIBLE: .*$", re.M)


@dataclass(frozen=True)
class PlannerConfig:
    """How to plan. ``free_teams`` lets the model pick any team (and refuse at will) instead of
    only the teams the catalogue says can do each sub-task. ``restate``: the allocation writes the
    decomposition's steps itself and the model picks robots and orchestration; off, the model
    rewrites the plan freely. ``world_check``: offer only steps that succeed in the scene from the
    state the steps so far produce (decomposition, and a restated allocation). ``chat_template``:
    "auto" gives an instruct model each prompt as a user turn of its own chat template; "none"
    gives raw text. ``candidates``: how many decompositions to write and how to choose one; ``goal_candidates``:
    how many goal statements to write (the sampled ones at the candidates' temperature), one kept; ``goal_check``:
    state the goals first (the goal stage), refuse a task whose stated goals the team cannot meet, and give the
    verifier the goals to check candidates against (with the grammar only)."""

    sampling: Sampling = Sampling()
    grammar: bool = True
    free_teams: bool = False
    prompts: PromptOptions = PromptOptions()
    budgets: dict[str, int] = field(default_factory=lambda: dict(DEFAULT_BUDGETS))
    chat_template: str = "auto"
    restate: bool = True
    world_check: bool = True
    candidates: Candidates = Candidates()
    goal_candidates: int = 1
    goal_check: bool = False
    stop_at_goals: bool = True
    repair: bool = True
    finish_goals: bool = True
    together: bool = True
    drop_errands: bool = True
    drop_idle: bool = True
    fold_finish: bool = True


class Planner:
    """Plans tasks with one backend; keeps nothing between tasks but the backend's cache."""

    def __init__(self, backend: Backend, catalogue: Catalogue, config: PlannerConfig = PlannerConfig(),
                 examples: Sequence[Example] | None = None, world: World | None = None,
                 progress: StageProgress = SILENT):
        """``world``: the world the tasks happen in (default AI2-THOR's; a site domain's, see
        :func:`~smartllm_local.worlds.world_of`), whose worked examples the prompts show unless given;
        ``progress`` hears of each stage as it runs (see :mod:`.progress`)."""
        self.backend = backend
        self.progress = progress
        self.catalogue = catalogue
        self.config = config
        self.world = world or Ai2ThorWorld()
        self.examples = list(examples) if examples is not None else load_examples(self.world.examples_dir())
        self.chat, self.chat_status = chat_format(backend, config.chat_template)
        self._shared: bool | None = None  # whether coalition and allocation share a prompt (see _shares_context)

    def scene(self, floor_plan: str | int) -> SceneObjects:
        """What the stages know of where a task happens: a floor plan's objects, or the site's entries."""
        return self.world.scene(floor_plan)

    def stage_rng(self, result: PlanResult, stage: str) -> np.random.Generator:
        """A stage's sampling randomness, from (seed, task, stage) alone: a task planned by itself
        samples what it samples in a full run, whatever ran before it."""
        task = json.dumps([result.instruction, result.floor_plan, list(result.robots), stage]).encode()
        words = np.frombuffer(hashlib.sha256(task).digest()[:16], dtype=np.uint32)
        return np.random.default_rng([self.config.sampling.seed, *(int(w) for w in words)])

    # ---------------------------------------------------------------- stages

    def decomposition_prompt(self, instruction: str, scene: SceneObjects, team: Sequence[Robot]) -> Fitted:
        """The decomposition's prompt as the model gets it: its tokens and where its shared prefixes end."""
        opts = self.config.prompts
        examples = examples_for("decomposition", self.examples, opts)
        return fit_prompt(lambda ex: decomposition_prompt(instruction, scene, self.catalogue, team, ex, opts),
                          examples, self.backend, self.config.budgets["decomposition"], self.chat)

    def steps(self) -> list[Step]:
        """SMART-LLM's stages as this planner's configuration has them, for :func:`~.steps.run_steps`: the goal
        stage where the goal check is on (with the grammar), the decomposition, the coalition unless it is off,
        and the allocation, which goes on in the coalition's context."""
        config = self.config
        goal = [Step("goal", self.check_goals)] if config.goal_check and config.grammar else []
        coalition = [Step("coalition", self.form_coalition)] if config.prompts.coalition else []
        return [*goal, Step("decomposition", self.decompose), *coalition,
                Step("allocation", self.allocate, follows=bool(coalition))]

    def decompose(self, result: PlanResult) -> StageRecord:
        """The decomposed plan, written for the task's team: its prompt and its grammar offer the team's
        skills, and only the calls the team can make (a step for several robots together included). With
        several candidates, the one the verifier (or the likelihood) chooses, the others in its record."""
        scene = self.scene(result.floor_plan)
        team = self.catalogue.team(result.robots)
        prompt = self.decomposition_prompt(result.instruction, scene, team)
        count = self.config.candidates.count
        if count == 1:
            record = self._decomposition(result, scene, team, prompt, self.backend, 0, self.progress)
        else:
            started = time.perf_counter()
            records = write_all(self.backend, count, lambda lane, k: self._decomposition(
                result, scene, team, prompt, lane, k, self.progress if k == 0 else SILENT))
            record = self._choose(result, scene, records)  # type: ignore[arg-type]
            record.seconds = time.perf_counter() - started
        self._tidy(record, result, scene)
        result.add(record)
        self._finish_plan_stage(record, result, form="decomposed", scene=scene, parsed=record.plan)
        return record

    def _tidy(self, record: StageRecord, result: PlanResult, scene: SceneObjects) -> None:
        """The chosen decomposition without its errands nobody asked for (:mod:`.errands`, and :mod:`.in_turn`'s
        steps that alone made sub-tasks run in turn) and its idle steps (:mod:`.idle_steps`, and openings
        :mod:`.opened_for_nothing`), things kept in hand
        put where the goals want them (:mod:`.kept_in_hand`), the planner's last sub-task folded into the model's
        last (:mod:`.finish_fold`), an opening made for another sub-task moved into it (:mod:`.opening_moved`),
        sub-tasks that could only run in turn joined (:mod:`.joined`): the text the coalition and the allocation
        read."""
        if not (self.config.world_check and isinstance(record.plan, Plan) and not record.plan.is_refusal):
            return
        skills, config, team = self.catalogue.skills, self.config, self.catalogue.team(result.robots)
        goals = stated_conditions(result, scene) if config.drop_errands or config.finish_goals else []
        if config.drop_errands:  # a thing named only to be left as it is ("except the floor lamp") is nobody's
            naming = load_state_words(scene.world.examples_dir()).without_excepted(result.instruction)
            record.output, record.errands = drop_errands(record.output, scene, skills, naming, goals)
            record.output, in_turn = free_blocks(record.output, scene, skills, team, naming, goals)
            record.errands += in_turn
        if config.drop_idle:
            record.output, record.idle_steps = drop_idle_steps(record.output, scene, skills)
            record.output, unused = drop_opened_for_nothing(record.output, scene, skills, result.instruction, goals)
            record.idle_steps += unused
        if config.finish_goals:
            record.output, record.put_away = put_kept_things(record.output, scene, skills, goals)
        into = None
        if config.fold_finish and record.finish is not None:
            record.output, into = fold_finish(record.output, scene, skills, team)
            if into is not None:
                record.finish = {**record.finish, "into": into}
        if config.together:
            record.output, record.moved = move_openings(record.output, scene, skills)
            record.output, record.joined = join_in_turn(record.output, scene, skills, team, goals)
        if record.errands or record.idle_steps or record.put_away or into is not None or record.joined or record.moved:
            record.plan = None  # parsed again, from the text the coalition and the allocation read

    def _decomposition(self, result: PlanResult, scene: SceneObjects, team: Sequence[Robot], prompt: Fitted,
                       backend: Backend, k: int, progress: StageProgress) -> StageRecord:
        """Candidate ``k`` of the decomposition, written on ``backend`` (the planner's, or a lane of it). With stated
        goals (which the goal check found the team can meet) it may not refuse: asked to switch a lamp off and open
        the blinds, the 1.5B refused for PutObject, a skill the team lacks and no goal needs (dev15-s5)."""
        opts = self.config.prompts
        record = StageRecord("decomposition", chat_template=self.chat_status)
        skills = self.catalogue.skills
        world = for_decomposition(scene, skills, MAX_SUBTASKS, team) if self.config.world_check else None
        config = self.config
        goals = stated_conditions(result, scene) if config.stop_at_goals or config.finish_goals else []
        repairer = Repairer(world, skills, stated=goals) if world is not None and (
            config.repair or config.finish_goals) and Repairer.fits(world) else None
        said = said_of(result.instruction, scene, goals, world.objects() if world is not None else ()) \
            if config.finish_goals else Said()
        constraint = PlanConstraint(scene, skills, comments=opts.comments, summary=opts.summary, world=world,
                                    for_team=team, goals=goals, said=said, repairer=repairer, allow_refusal=not goals,
                                    stop=config.stop_at_goals, repair=config.repair, finish=config.finish_goals,
                                    cost=spelled_cost(backend)) if config.grammar else None
        rng = self.stage_rng(result, record.stage if k == 0 else f"{record.stage} candidate {k}")
        run_stage(record, backend, prompt, constraint, output_budget=self.config.budgets["decomposition"],
                  sampling=self.config.candidates.sampling(self.config.sampling, k), rng=rng, progress=progress)
        self._finish_plan_stage(record, PlanResult(result.instruction, result.floor_plan, result.robots),
                                form="decomposed", scene=scene)
        if constraint is not None:
            record.ended_at_goals = constraint.ended_at_goals
            record.finish = constraint.finish_made
            if constraint.repairs is not None:
                record.repairs, record.unrepaired = constraint.repairs.made, len(constraint.repairs.missed)
        if record.refusal is not None and constraint is not None and constraint.must_refuse:
            record.refused_by = "grammar"  # the team can make no call in this scene
        return record

    def _choose(self, result: PlanResult, scene: SceneObjects, records: Sequence[StageRecord]) -> StageRecord:
        """The candidate with the best score, its record carrying every candidate's text, check and score. A
        refusal or a broken plan scores below every plan."""
        settings = self.config.candidates
        conditions = stated_conditions(result, scene)
        summaries, scores = [], []
        for k, record in enumerate(records):
            mean = mean_logprob(record.logprob, record.choices)
            check = None
            if isinstance(record.plan, Plan) and not record.plan.is_refusal:
                check = check_decomposition(record.plan, scene, self.catalogue.skills, conditions,
                                            idle=settings.select == "verifier")
            value = -math.inf if check is None else mean if settings.select == "likelihood" else \
                score(check, mean, settings.weights)
            scores.append(value)
            sampling = settings.sampling(self.config.sampling, k)
            summaries.append({"candidate": k, "temperature": sampling.temperature, "seed": sampling.seed,
                              "output": record.output, "refusal": record.refusal, "error": record.error or None,
                              "generated_tokens": record.generated_tokens, "seconds": round(record.seconds, 3),
                              "mean_logprob": round(mean, 4), "check": check.as_dict() if check else None,
                              "score": None if math.isinf(value) else round(value, 4)})
        best = choose(scores)
        chosen = records[best]
        for k, summary in enumerate(summaries):
            summary["chosen"] = k == best
        chosen.candidates = summaries
        return chosen

    def form_coalition(self, result: PlanResult) -> StageRecord:
        """The coalition, in a context that leaves room for the allocation to go on in it."""
        decomposed, team, scene = self._decomposed(result)
        opts = self.config.prompts
        record = StageRecord("coalition", chat_template=self.chat_status)
        decomposition = result.stage("decomposition").output
        examples = examples_for("coalition", self.examples, opts)
        floor = self.config.budgets["coalition"]
        shared = self._shares_context(scene)
        reserve = self._allocation_setup(result, decomposed, team, scene)[1] + self._glue_tokens() if shared else 0
        prompt = fit_prompt(lambda ex: self._coalition_prompt(decomposition, team, scene, ex, shared), examples,
                            self.backend, floor + reserve, self.chat)
        names = [f.name for f in decomposed.functions]
        needs = function_needs(decomposed, scene, self.catalogue.skills.lifting)
        together = started_together(decomposition, calls_too=self.config.together)
        constraint = CoalitionConstraint(names, team, needs=[needs[n] for n in names], free=self.config.free_teams,
                                         blocks=together) if self.config.grammar else None
        budget = floor
        if constraint is not None:
            # The configured budget is a floor: the reasoning may use all the context the prompt and the
            # allocation leave (the constraint ends the output once every sub-task has its line).
            budget = max(floor, self.backend.n_ctx - len(prompt.tokens) - reserve - 1)
        run_stage(record, self.backend, prompt, constraint, output_budget=budget,
                  sampling=self.config.sampling, rng=self.stage_rng(result, record.stage), progress=self.progress)
        if constraint is None:
            lines = [line for line in record.output.splitlines() if line.strip()]
            bad = [line for line in lines if not _COALITION_LINE.match(line)]
            if bad or not lines:
                record.error = f"coalition output is not a list of coalition lines: {bad[:1] or 'empty'}"
            elif lines[0].startswith(REFUSAL_PREFIX):
                record.refusal = lines[0][len(REFUSAL_PREFIX):].strip()
        if record.refusal is not None:
            result.refusal = record.refusal
            record.refused_by = "grammar" if constraint is not None and constraint.must_refuse else "model"
        result.add(record)
        return record

    def allocate(self, result: PlanResult) -> StageRecord:
        """The allocated plan: in the context the coalition left, where the two share a prompt; otherwise
        from a prompt of its own (with the coalition's output, where it ran)."""
        decomposed, team, scene = self._decomposed(result)
        coalition = result.stages.get("coalition")
        record = StageRecord("allocation", chat_template=self.chat_status)
        constraint, budget = self._allocation_setup(result, decomposed, team, scene)
        if coalition is not None and self._shares_context(scene):
            prompt = self._after_coalition(result, coalition, team, scene, budget)
        else:
            decomposition, opts = result.stage("decomposition").output, self.config.prompts
            text = coalition.output if coalition is not None else None
            prompt = fit_prompt(lambda ex: allocation_prompt(decomposition, text, team, self.catalogue.skills,
                                                             self.catalogue.robots, ex, opts),
                                examples_for("allocation", self.examples, opts), self.backend, budget, self.chat)
        run_stage(record, self.backend, prompt, constraint, output_budget=budget,
                  sampling=self.config.sampling, rng=self.stage_rng(result, record.stage), progress=self.progress)
        self._finish_plan_stage(record, result, form="allocated", scene=scene, team_size=len(team))
        self._executable(record, result, scene, team)
        result.add(record)
        return record

    def _executable(self, record: StageRecord, result: PlanResult, scene: SceneObjects, team: Sequence[Robot]) -> None:
        """With the grammar's world check, the allocated plan changed until the team's run fails no call
        (:mod:`.executable`); refused where no call of it succeeds."""
        config = self.config
        if not (config.grammar and config.world_check and isinstance(record.plan, Plan) and not record.plan.is_refusal):
            return
        made = for_team(record.output, record.plan, scene, team, self.catalogue.skills)
        record.output, record.plan, record.executable = made.text, made.plan, made.changes
        if made.refusal is not None:
            record.refusal = result.refusal = made.refusal
            record.refused_by = WORLD_CHECK
            record.output = f"{REFUSAL_PREFIX}{made.refusal}\n"
            record.plan = parse_plan(record.output, form="allocated")

    def _decomposed(self, result: PlanResult) -> tuple[Plan, list[Robot], SceneObjects]:
        """What the stages after the decomposition start from: its plan, the task's team and its scene."""
        return (result.stage("decomposition").plan, self.catalogue.team(result.robots),  # type: ignore[return-value]
                self.scene(result.floor_plan))

    def _allocation_setup(self, result: PlanResult, decomposed: Plan, team: Sequence[Robot],
                          scene: SceneObjects) -> tuple[Constraint | None, int]:
        """The allocation's constraint and output budget (which the coalition keeps room for)."""
        decomposition = result.stage("decomposition").output
        skills = self.catalogue.skills
        names = [f.name for f in decomposed.functions]
        constraint: Constraint | None = None
        if self.config.grammar and self.config.restate:
            world = (WorldCheck(scene, skills, len(team))
                     if self.config.world_check else None)
            coalition = result.stages.get("coalition")
            constraint = RestatedAllocation(scene, skills, team=len(team) if self.config.free_teams else team,
                                            function_names=names, bodies=restated_bodies(decomposition, names),
                                            world=world, together=self.config.together,
                                            chosen=chosen_teams(coalition.output) if coalition is not None else None)
        elif self.config.grammar:
            team_skills = [s for s in skills.values() if any(s.name in r.skills for r in team)]
            constraint = PlanConstraint(scene, SkillSet(team_skills), team_size=len(team),
                                        comments=self.config.prompts.comments,
                                        function_names=names, team=None if self.config.free_teams else team,
                                        together=self.config.together)
        # Restating, the output's length is known to the character; rewriting, it is estimated.
        if isinstance(constraint, RestatedAllocation):
            return constraint, exact_budget(constraint.maximum_output())
        # never below what the shortest complete allocation needs
        minimum = constraint.minimum_budget() if isinstance(constraint, PlanConstraint) else 0
        written = allocation_budget(result.stage("decomposition"), len(names), self.config.budgets["allocation"])
        return constraint, max(written, minimum)

    def _coalition_prompt(self, decomposition: str, team: Sequence[Robot], scene: SceneObjects,
                          examples: Sequence[Example], shared: bool = True) -> Prompt:
        return coalition_prompt(decomposition, team, scene, self.catalogue.skills, self.catalogue.robots, examples,
                                self.config.prompts, allocations=shared)

    def _shares_context(self, scene: SceneObjects) -> bool:
        """Whether coalition and allocation share one prompt: where the model's context holds its examples,
        a coalition's and an allocation's budgets and a task's own part (:data:`OWN_PART`). A shorter
        context (a Llama-2's 4,096 tokens) gets the paper's two prompts, which keep more examples."""
        if self._shared is None:  # the examples are the same for every task a planner plans
            examples = examples_for("coalition", self.examples, self.config.prompts)
            _, tokens, prefixes = prompt_tokens(self.backend, self._coalition_prompt("", [], scene, examples),
                                                self.chat)
            need = (prefixes or (len(tokens),))[0] + self.config.budgets["coalition"] + \
                self.config.budgets["allocation"] + OWN_PART
            self._shared = need <= self.backend.n_ctx
        return self._shared

    def _glue_tokens(self) -> int:
        return len(self.backend.tokenize_continuation(ALLOCATION_GLUE))

    def _after_coalition(self, result: PlanResult, coalition: StageRecord, team: Sequence[Robot],
                         scene: SceneObjects, budget: int) -> Fitted:
        """The coalition's context (its prompt with the examples it kept, and the tokens it wrote, or its output
        tokenized where they were not kept: free text), then the line that opens the allocation. Only
        where they were kept does the backend go on from its cache (``continues``)."""
        kept = [e for e in examples_for("coalition", self.examples, self.config.prompts)
                if e.name in coalition.examples]
        dropped = [e for e in self.examples if e.name in coalition.dropped]
        text, tokens, prefixes = prompt_tokens(
            self.backend, self._coalition_prompt(result.stage("decomposition").output, team, scene, kept), self.chat)
        live = coalition.context[:len(tokens)] == tokens
        written = coalition.context[len(tokens):] if live else self.backend.tokenize_continuation(coalition.output)
        context = tokens + written + self.backend.tokenize_continuation(ALLOCATION_GLUE)
        if len(context) + budget >= self.backend.n_ctx:
            raise UserError(f"the coalition's context ({len(context)} tokens) and the allocation's output budget "
                            f"({budget} tokens) exceed the model's context of {self.backend.n_ctx} tokens; "
                            "raise --n-ctx")
        # A coalition that asked the model nothing left its prompt unevaluated: the allocation loads its prefixes.
        return Fitted(text + coalition.output + ALLOCATION_GLUE, context, prefixes, kept, dropped,
                      continues=live and coalition.prompted)

    def _finish_plan_stage(self, record: StageRecord, result: PlanResult, *, form: str, scene: SceneObjects,
                           team_size: int | None = None, parsed: object = None) -> None:
        plan = parsed if parsed is not None else check_output(record, lambda text: parse_plan(
            text, form=form, skills=self.catalogue.skills, team_size=team_size, scene_types=scene.types,  # type: ignore[arg-type]
            name=f"<{record.stage} output>"))
        if isinstance(plan, Plan) and plan.is_refusal:
            record.refusal = plan.refusal
        if record.refusal is not None:
            result.refusal = record.refusal
        if record.error:
            result.error = record.error
        record.plan = plan

    def check_goals(self, result: PlanResult) -> StageRecord:
        """The goal stage for a task, and the check of what it stated against the team: a stated condition no
        plan of this team can meet (a state no robot's skill gives, a closed fridge nobody can open, a load too
        heavy for every lifter together) refuses the task, with that reason. The model may not refuse here (it
        refused feasible tasks for untrue reasons, measured): a task is refused for what the world shows. A goal
        out of reach that nobody asked for is dropped instead, where a goal asked for is left (:mod:`.asked`)."""
        scene = self.scene(result.floor_plan)
        stated = state_goals(self, result.instruction, scene.floor_plan, refusals=False)
        record = stated.record
        conditions = stated_conditions(result, scene, record)
        team = self.catalogue.team(result.robots)
        problems = checked_against_team(record, result.instruction, scene, conditions, team, self.catalogue.skills) \
            if stated.statement else {}
        if any(problems.values()):
            record.refusal, record.refused_by = "; ".join(p for why in problems.values() for p in why), GOAL_CHECK
        if record.refusal is not None:
            result.refusal = record.refusal
        result.add(record)
        return record

    def goals(self, instruction: str, floor_plan: str | int) -> StatedGoals:
        """The goal stage, on demand: what must hold when the task is done, stated from the instruction and the
        scene alone (no team, no task file; see :mod:`.goal_stage`). :meth:`plan` does not run it."""
        return state_goals(self, instruction, floor_plan)

    # ------------------------------------------------------------------ task

    def plan(self, instruction: str, floor_plan: str | int, robot_ids: Sequence[int],
             steps: Sequence[Step] | None = None) -> PlanResult:
        """All stages for one task (:meth:`steps`, or another method's ``steps``); the allocated plan (or the
        refusal) is in the result."""
        self.catalogue.team(robot_ids)  # an unknown robot fails here, before any stage runs
        scene = self.scene(floor_plan)
        result = PlanResult(instruction=instruction, floor_plan=scene.floor_plan, robots=list(robot_ids))
        run_steps(self.steps() if steps is None else steps, result)
        self.conclude(result)
        return result

    @staticmethod
    def conclude(result: PlanResult) -> None:
        """Set the allocated plan text: the allocation's plan, or the refusal."""
        if result.refusal is not None:
            result.allocated = f"{REFUSAL_PREFIX}{result.refusal}\n"
            result.plan = parse_plan(result.allocated, form="allocated")
            return
        allocation = result.stages.get("allocation")
        if allocation is not None and not allocation.error:
            result.allocated = allocation.output
            result.plan = allocation.plan  # type: ignore[assignment]


STAGE_FILES = ("prompt.txt", "grammar.gbnf", "raw_output.txt", "timings.json", "candidates.json")
STAGE_OUTPUTS = {"decomposition": "decomposed.py", "coalition": "coalition.txt", "allocation": "allocated.py",
                 "goal": "goals.txt"}


def write_artifacts(result: PlanResult, out: Path, extra: dict | None = None) -> None:
    """Write prompts, grammars, raw outputs, timings and the stage outputs under ``out``.

    Artifacts an earlier run left in ``out`` for stages not run this time (``--no-coalition``, a
    refusal, a failed stage) are removed, so the folder shows this run only; nothing else in
    ``out`` is touched.
    """
    out = Path(out)
    written: set[Path] = set()

    def write(path: Path, text: str) -> None:
        write_atomic(path, text)
        written.add(path)

    for record in result.stages.values():
        folder = out / record.stage
        write(folder / "prompt.txt", record.prompt)
        if record.grammars:
            write(folder / "grammar.gbnf", "".join(
                f"# grammar {k + 1} of {len(record.grammars)} offered for a line of this stage\n{g}\n"
                for k, g in enumerate(record.grammars)))
        write(folder / "raw_output.txt", record.raw)
        write(folder / "timings.json", json_text(record.timings()))
        if record.candidates:
            write(folder / "candidates.json", json_text(record.candidates))
        write(out / STAGE_OUTPUTS[record.stage], record.output)
    summary = {
        "instruction": result.instruction, "floor_plan": result.floor_plan, "robots": result.robots,
        "refusal": result.refusal, "error": result.error or None, "notices": result.notices,
        "stages": {name: r.timings() for name, r in result.stages.items()},
        **(extra or {}),
    }
    write(out / "result.json", json_text(summary))
    if result.allocated and "allocation" not in result.stages:
        write(out / "allocated.py", result.allocated)
    _remove_stale_artifacts(out, written)


def _remove_stale_artifacts(out: Path, written: set[Path]) -> None:
    """Remove the files write_artifacts writes that this run did not write; a stage folder goes
    too once it is empty. Anything else (the user's files, other folders) stays."""
    for stage, output in STAGE_OUTPUTS.items():
        candidates = [out / output, *(out / stage / name for name in STAGE_FILES)]
        for path in candidates:
            if path not in written and path.is_file() and not path.is_symlink():
                try:
                    path.unlink()
                except OSError as exc:
                    raise UserError(f"cannot remove the stale artifact {path}: {exc.strerror or exc}") from exc
        folder = out / stage
        if folder.is_dir() and not folder.is_symlink() and not any(folder.iterdir()):
            folder.rmdir()


def restore_stage(result: PlanResult, record: StageRecord, skills: SkillSet, scene: SceneObjects,
                  team_size: int) -> None:
    """Put back a stage that an interrupted run finished, its plan parsed again from its output.

    Raises:
        PlanError: the saved output is not the plan it claims to be (the record is not to be trusted).
    """
    if record.stage in ("decomposition", "allocation") and not record.error:
        form = "decomposed" if record.stage == "decomposition" else "allocated"
        record.plan = parse_plan(record.output, form=form, skills=skills,  # type: ignore[arg-type]
                                 team_size=team_size if form == "allocated" else None,
                                 scene_types=scene.types, name=f"<saved {record.stage} output>")
        if (record.refusal is None) != (not record.plan.is_refusal):  # type: ignore[union-attr]
            raise PlanError(f"the saved {record.stage} output and its record disagree on refusing")
    if record.refusal is not None:
        result.refusal = record.refusal
    if record.error and record.stage in ("decomposition", "allocation"):
        result.error = record.error
    result.add(record)
