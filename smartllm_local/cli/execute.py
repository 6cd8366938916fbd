"""``smartllm-local execute``: run an allocated plan file with a robot team (in AI2-THOR, or on a site
domain's site) and score it with the paper's metrics."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from ..benchmark.tasks import find_task, load_tasks
from ..domain import load_domain
from ..errors import UserError
from ..executor import Execution
from ..files import check_output_file, read_json, write_json
from ..plan_language import read_plan
from ..robots import parse_robot_ids
from ..scoring import Scores, parse_goals, score_execution
from ..worlds import with_catalogue, world_of
from .dispatch import run_record
from .options import (
    CATALOGUE_HELP,
    DOMAIN_HELP,
    THOR_BUILD_HELP,
    check_transitions,
    given_path,
    refuse_household_options,
)


def execute(
    plan: Path = typer.Argument(..., help="The allocated plan file (.py)."),
    floor_plan: str | None = typer.Option(None, help="Floor plan, e.g. 6 or FloorPlan6."),
    robots: str | None = typer.Option(None, help="The team as catalogue ids, e.g. 1,2,3; robots[i] is the i-th."),
    goal: Path | None = typer.Option(None, help='Goal conditions: a JSON list of {"name", "contains", "state"}.'),
    trans: int | None = typer.Option(None, help="Ground-truth transitions (for RU and SR)."),
    max_trans: int | None = typer.Option(None, help="Maximum transitions (for RU and SR)."),
    tasks: Path | None = typer.Option(None, help="A task file to take the floor plan, robots and goals from."),
    task: str | None = typer.Option(None, help="The task id in --tasks (default: the project's benchmark)."),
    as_json: bool = typer.Option(False, "--json", help="Print the metrics as one JSON object."),
    trace: Path | None = typer.Option(None, parser=given_path, metavar="FILE",
                                      help="Write every primitive action to this JSON file."),
    catalogue: Path | None = typer.Option(None, help=CATALOGUE_HELP),
    thor_build: Path | None = typer.Option(None, help=THOR_BUILD_HELP),
    domain: str | None = typer.Option(None, help=DOMAIN_HELP),
) -> None:
    """Run a plan with a robot team (in AI2-THOR, or on a site domain's site) and print SR, TCR, GCR, RU and Exe."""
    given_transitions = trans is not None or max_trans is not None
    if trace is not None:
        check_output_file(trace, "--trace")
    dom = with_catalogue(load_domain(domain), catalogue)
    cat, world = dom.catalogue, world_of(dom)
    refuse_household_options(dom, floor_plan, thor_build)
    if task is not None:
        if floor_plan or robots or goal:
            raise UserError("give either --task (with --tasks) or --floor-plan/--robots/--goal, not both")
        chosen = find_task(load_tasks(tasks or dom.task_files(), catalogue=cat, domain=dom), task)
        scene, team_ids, goals = chosen.floor_plan, list(chosen.robots), list(chosen.goals)
        trans = chosen.trans if trans is None else trans
        max_trans = chosen.max_trans if max_trans is None else max_trans
    else:
        if tasks is not None:
            raise UserError("--tasks needs --task ID")
        floor_plans = "--floor-plan" in world.options  # else every task is on the world's one place
        if not ((floor_plan or not floor_plans) and robots and goal):
            raise UserError("execute needs --floor-plan, --robots and --goal (or --task ID)" if floor_plans
                            else "execute needs --robots and --goal (or --task ID)")
        scene = world.scene_name(floor_plan)
        team_ids = parse_robot_ids(robots)
        goals = list(parse_goals(read_json(goal, "goal file"), where=str(goal), states=world.task_rules().goal_states))
        if not goals:
            raise UserError(f"goal file {goal}: a goal file needs at least one condition, "
                            'e.g. [{"name": "Fridge", "contains": ["Apple"], "state": null}]')
    if given_transitions:
        check_transitions(trans, max_trans)
    team = cat.team(team_ids)
    parsed = read_plan(plan, form="allocated", skills=cat.skills, team_size=len(team),
                       scene_types=world.plan_types(scene))
    execution = world.run(parsed, scene, team, skills=cat.skills, build=str(thor_build) if thor_build else None)
    scores = score_execution(execution, goals, trans=trans, max_trans=max_trans)
    if trace is not None:
        write_json(trace, {"plan": str(plan), "floor_plan": scene, "robots": team_ids, **run_record(execution)})
    _print_run(plan, scene, team_ids, execution, scores, as_json)


def _print_run(plan: Path, scene: str, team_ids: list[int], execution: Execution, scores: Scores,
               as_json: bool) -> None:
    if as_json:
        typer.echo(json.dumps(scores.metrics()))
        return
    typer.echo(f"{plan} on {scene} with robots {team_ids}: {execution.succeeded}/{execution.attempted} actions "
               f"succeeded in {execution.ticks} ticks, {execution.transitions} transition(s)")
    for entry in execution.trace:
        if not entry.success:
            typer.echo(f"  tick {entry.tick}: {entry.skill}{tuple(entry.objects)} by {entry.robots} "
                       f"failed: {entry.error}")
    for line in metrics_lines(scores, fix="give --trans and --max-trans (or --task ID)"):
        typer.echo(line)


def metrics_lines(scores: Scores, *, fix: str, transitions: bool = False) -> list[str]:
    """Each goal condition met or not, the metrics, and why any is n/a (there were no goal conditions to judge
    the run by, or no expected and maximum transitions), with ``fix``, what would give them."""
    fmt = lambda v: "n/a" if v is None else f"{v:.2f}"  # noqa: E731
    lines = [f"  [{'x' if ok else ' '}] {description}" for description, ok in scores.conditions]
    lines.append(f"SR {fmt(scores.SR)}  TCR {fmt(scores.TCR)}  GCR {fmt(scores.GCR)}  RU {fmt(scores.RU)}  "
                 f"Exe {fmt(scores.Exe)}" + (f"  transitions {scores.transitions}" if transitions else ""))
    missing = []
    if scores.GCR is None:
        missing.append("goal conditions (TCR and GCR are judged by them, and SR needs TCR)")
    if scores.RU is None:
        missing.append("expected and maximum transitions (RU is judged by them, and SR needs RU)")
    if missing:
        lines.append(f"n/a: no {' and no '.join(missing)}; {fix}")
    return lines
