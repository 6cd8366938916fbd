"""``smartllm-local plan``: one task through the planner on a local model, then (optionally) executed in
AI2-THOR or on a site, or dispatched to a lab's robots."""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import typer

from ..benchmark.methods import METHODS, MODEL_FREE, Method, check_time_limit, make_method
from ..benchmark.run import execute_scored
from ..benchmark.tasks import Task, find_task, given_task, has_words, load_tasks
from ..benchmark.trace_file import TRACE, write_trace
from ..domain import Domain, load_domain
from ..errors import UserError
from ..executor import Execution
from ..executor.dispatch import Dispatch, dispatch_plan, load_dispatch
from ..files import check_output_folder
from ..planner.backends import Backend
from ..planner.goal_stage import StatedGoals, restated_goals
from ..planner.models import default_model
from ..planner.pipeline import Planner, write_artifacts
from ..planner.prompting.goal_prompt import load_goal_examples
from ..planner.result import PlanResult
from ..robots import Catalogue, Robot, parse_robot_ids
from ..scoring import Scores
from ..world.controller import check_build
from ..worlds import with_catalogue, world_of
from .dispatch import dispatch_report, dispatch_succeeded, run_record
from .execute import metrics_lines
from .options import (
    CATALOGUE,
    DOMAIN,
    PLANNER_TIME_LIMIT,
    READ_STEPS,
    TASKS,
    THOR_BUILD,
    ModelOptions,
    given_path,
    model_options,
    refuse_household_options,
)
from .progress import PlanProgress

#: The methods ``plan`` offers: those that plan with the model (the others plan from a benchmark task's goals or
#: its reference plan, in ``benchmark run``).
PLAN_METHODS = tuple(m for m in METHODS if m not in MODEL_FREE)


@model_options(without=("parallel",))  # one task: nothing to plan at once with it
def plan_command(
    instruction: str | None = typer.Argument(None, help="What the robots should do (or use --task)."),
    floor_plan: str | None = typer.Option(None, help="Floor plan, e.g. 15 or FloorPlan15."),
    robots: str | None = typer.Option(None, help="The team as catalogue ids, e.g. 1,2,3."),
    tasks: Path | None = TASKS,
    task: str | None = typer.Option(None, help="Plan this task of --tasks, with its floor plan and robots."),
    out: Path | None = typer.Option(None, parser=given_path, metavar="DIR", help=(
        "Write prompts, grammars, raw outputs and timings here.")),
    execute: bool = typer.Option(False, "--execute", help="Run the plan in AI2-THOR and print the metrics."),
    dispatch: Path | None = typer.Option(None, "--dispatch", metavar="LAB.toml", help=(
        "Run the plan on the lab's robots: each skill call goes to the function this dispatch file names "
        "for it (see smartllm-local dispatch); exit 1 if an action failed.")),
    method: str = typer.Option("smartllm", help=(
        f"{', '.join(PLAN_METHODS)}: SMART-LLM's stages; the model's decomposition with robots at random (seeded) "
        "or by a rule; the model states the goal and Fast Downward finds the steps (see `benchmark run`).")),
    planner_time_limit: float = PLANNER_TIME_LIMIT,
    read_steps: bool = READ_STEPS,
    goals: bool = typer.Option(False, "--goals", help=(
        "Also state the task's goals (the goal stage: what must hold when it is done, from the instruction and "
        "the scene alone); print them after the plan and write goals.txt with --out.")),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help=(
        "Show no progress. Otherwise each stage is shown on stderr as it runs (on a terminal, its tokens, their "
        "rate and its time live; elsewhere a line per stage as it ends); stdout holds the plan either way.")),
    catalogue: Path | None = CATALOGUE,
    thor_build: Path | None = THOR_BUILD,
    domain: str | None = DOMAIN,
    *,
    model_settings: dict[str, Any],
) -> None:
    """Plan a task with a local model: decomposition, coalition, allocation (or another --method); print the
    allocated plan."""
    options = ModelOptions(**model_settings)
    _check_method(method, planner_time_limit)
    if out is not None:
        check_output_folder(out, "--out")
    dom = with_catalogue(load_domain(domain), catalogue)
    refuse_household_options(dom, floor_plan, thor_build)
    if goals or options.config.goal_check or method == "goal-planner":
        load_goal_examples(dom.prompts_dir())  # a domain without them fails before the model loads
    instruction, scene, team_ids, chosen = _what_to_plan(dom, instruction, floor_plan, robots, tasks, task)
    team = dom.catalogue.team(team_ids)
    functions = _where_to_run(dom, team, execute=execute, dispatch=dispatch, thor_build=thor_build)
    planner, result, stated = _plan(options, dom, chosen or given_task(instruction, scene, team_ids),
                                    lambda planner: make_method(method, dom.catalogue, planner,
                                                                planner_time_limit=planner_time_limit,
                                                                world=world_of(dom), read_steps=read_steps),
                                    quiet=quiet, goals=goals)
    for notice in result.notices:
        print(f"notice: {notice}", file=sys.stderr)
    execution, scores, dispatched = _run_plan(result, chosen, dom, team, functions, execute=execute,
                                              thor_build=thor_build)
    extra = _record(planner, method, scores, dispatched, stated)
    if out is not None:
        _write_out(out, result, extra, execution, scores)
    _print_result(result, extra, scores, dispatched, as_json, chosen)
    if stated is not None and not as_json:
        typer.echo(stated.report(), nl=False)
    if result.error or (dispatched is not None and not dispatch_succeeded(dispatched)):
        raise typer.Exit(1)


def _where_to_run(dom: Domain, team: list[Robot], *, execute: bool, dispatch: Path | None,
                  thor_build: Path | None) -> Dispatch | None:
    """Check where the plan is to run (AI2-THOR's build, the lab's dispatch file) before the model loads, so a
    mistake there costs no planning; the dispatch file's functions, if one is given."""
    if execute and dispatch is not None:
        raise UserError("give --execute (in AI2-THOR) or --dispatch (on the lab's robots), not both")
    if "--thor-build" in world_of(dom).options and (execute or thor_build is not None):
        check_build(thor_build)
    return _dispatch_functions(dispatch, dom.catalogue, team)


def _run_plan(result: PlanResult, chosen: Task | None, dom: Domain, team: list[Robot], functions: Dispatch | None,
              *, execute: bool, thor_build: Path | None
              ) -> tuple[Execution | None, Scores | None, Execution | None]:
    """Execute the plan and score it (``--execute``) or dispatch it to the lab (``--dispatch``), where there is a
    plan: the execution and its scores, and the dispatched run (None for what was not asked or not done)."""
    planned = result.plan is not None and not result.error
    scores = execution = None
    if execute and planned:
        execution, scores = execute_scored(result, chosen.goals if chosen else (), dom.catalogue,
                                           trans=chosen.trans if chosen else None,
                                           max_trans=chosen.max_trans if chosen else None,
                                           build=str(thor_build) if thor_build else None, world=world_of(dom))
    dispatched = None
    if functions is not None and planned and not result.plan.is_refusal:
        dispatched = dispatch_plan(result.plan, team, functions, skills=dom.catalogue.skills)
    return execution, scores, dispatched


def _record(planner: Planner, method: str, scores: Scores | None, dispatched: Execution | None,
            stated: StatedGoals | None) -> dict[str, Any]:
    """What the plan's record holds besides the plan (the method, the model, and the metrics, dispatch and goals
    where they were asked for): printed with ``--json`` and written with ``--out``."""
    extra: dict[str, Any] = {"method": method, "model": planner.backend.model, "backend": planner.backend.name,
                             "chat_template": planner.chat_status}
    if scores is not None:
        extra["metrics"] = scores.metrics()
    if dispatched is not None:
        extra["dispatch"] = {"attempted": dispatched.attempted, "succeeded": dispatched.succeeded,
                             **run_record(dispatched)}
    if stated is not None:
        extra["goals"] = stated.summary()
    return extra


def _write_out(out: Path, result: PlanResult, extra: dict[str, Any], execution: Execution | None,
               scores: Scores | None) -> None:
    """Write the plan's artifacts to ``--out``, with the execution's trace where it ran (a trace an earlier plan
    left there is removed, since it is not this plan's)."""
    write_artifacts(result, out, extra)
    if execution is not None and scores is not None:
        write_trace(out, execution, scores, result.floor_plan, result.robots)
    else:
        (out / TRACE).unlink(missing_ok=True)


def _check_method(method: str, planner_time_limit: float) -> None:
    """A method ``plan`` cannot run, or a time limit the goal-planner cannot keep, is an error before anything
    loads."""
    if method in MODEL_FREE:
        raise UserError(f"--method {method} plans with no model, from a benchmark task's "
                        f"{'goal conditions' if method.startswith('goal-planner') else 'reference plan'}: run it "
                        f"with `smartllm-local benchmark run --method {method} --task ID --out DIR`; plan offers "
                        f"{', '.join(PLAN_METHODS)}")
    if method not in PLAN_METHODS:
        raise UserError(f"--method must be one of {', '.join(PLAN_METHODS)}, not {method!r}")
    if method.startswith("goal-planner"):
        check_time_limit(planner_time_limit)


def _plan(options: ModelOptions, dom: Domain, task: Task, method_for: Callable[[Planner], Method], *, quiet: bool,
          goals: bool) -> tuple[Planner, PlanResult, StatedGoals | None]:
    """Load the model and plan ``task`` with the method ``method_for`` makes on the model's planner, then state
    the goals if asked, each stage shown on stderr as it runs (unless ``quiet``)."""
    with PlanProgress(quiet=quiet) as progress:
        model = options.model or ("the served model" if options.backend == "server" else default_model())
        with progress.loading(f"the model {model}"):
            planner = options.planners(dom.catalogue, dom)[0]
        try:
            planner.progress, progress.kept = progress, examples_kept(planner.backend)
            steps = method_for(planner).steps(task)
            result = planner.plan(task.instruction, task.floor_plan, task.robots, steps=steps)
            stated = None
            if goals:  # the goal check's statement where it ran; else the goal stage now, written to --out too
                ran = result.stages.get("goal")
                stated = restated_goals(ran, planner.scene(task.floor_plan)) if ran else \
                    planner.goals(task.instruction, task.floor_plan)
                if ran is None:
                    result.add(stated.record)
            return planner, result, stated
        finally:
            planner.backend.close()


def examples_kept(backend: Backend) -> str | None:
    """Where the examples' states evaluated in a run are kept for later, for the progress display (None: the
    backend does not say what it reused, as a server may not)."""
    store = getattr(backend, "prefix_store", None)
    if store is not None:
        return f"they are now kept in the prefix store {store.folder}, and later runs on this model start from them"
    if backend.name == "llamacpp":
        return "with --prefix-cache off they are kept for this run only"
    if backend.name == "transformers":
        return "the transformers backend keeps them for this run only"
    return None


def _what_to_plan(dom: Domain, instruction: str | None, floor_plan: str | None, robots: str | None,
                  tasks: Path | None, task: str | None) -> tuple[str, str, list[int], Task | None]:
    """The instruction, scene and team (and the task, for its goals) from ``--task`` or from the options."""
    if task is not None:
        if instruction or floor_plan or robots:
            raise UserError("give either --task (with --tasks) or an instruction with --floor-plan and --robots")
        chosen = find_task(load_tasks(tasks or dom.task_files(), catalogue=dom.catalogue, domain=dom), task)
        return chosen.instruction, chosen.floor_plan, list(chosen.robots), chosen
    if tasks is not None:
        raise UserError("--tasks needs --task ID")
    world = world_of(dom)
    floor_plans = "--floor-plan" in world.options  # else every task is on the world's one place
    if not (instruction and (floor_plan or not floor_plans) and robots):
        raise UserError('plan needs an instruction, --floor-plan and --robots (or --task ID), e.g. '
                        'smartllm-local plan "Put the apple in the fridge" --floor-plan 6 --robots 1,2'
                        if floor_plans else "plan needs an instruction and --robots (or --task ID)")
    if not has_words(instruction):
        raise UserError(f"the instruction {instruction!r} has no words: say what the robots should do, "
                        'e.g. "Put the apple in the fridge"')
    return instruction.strip(), world.scene_name(floor_plan), parse_robot_ids(robots), None


def _dispatch_functions(dispatch: Path | None, cat: Catalogue, team: list[Robot]) -> Dispatch | None:
    """The lab's functions for ``--dispatch``: one for every skill of the team, since the grammars offer them all."""
    if dispatch is None:
        return None
    functions = load_dispatch(dispatch, cat.skills)
    missing = functions.unnamed(skill for robot in team for skill in robot.skills)
    if missing:
        raise UserError(f"the team's robots have skill(s) {', '.join(missing)}, which the dispatch file "
                        f"{dispatch} names no function for; add them under [skills]")
    return functions


def _print_result(result: PlanResult, extra: dict[str, Any], scores: Scores | None,
                  dispatched: Execution | None, as_json: bool, chosen: Task | None) -> None:
    if as_json:
        typer.echo(json.dumps({"allocated": result.allocated, "refusal": result.refusal,
                               "error": result.error or None, **extra}))
        return
    typer.echo(result.allocated or f"# no valid plan: {result.error}\n", nl=False)
    if scores is not None:
        fix = f"task {chosen.id} gives none" if chosen is not None else \
            "a free instruction has neither: plan --task ID to score against a task's"
        for line in metrics_lines(scores, fix=fix, transitions=True):
            typer.echo(line)
    if dispatched is not None:
        typer.echo("dispatched: " + "\n".join(dispatch_report(dispatched)))
