"""``smartllm-local validate``, ``execute`` and ``dispatch``: check plan files, run them (in AI2-THOR or on a
site domain's site) or on a lab's robots."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import typer

from ..domain import Domain, load_domain
from ..errors import UserError
from ..executor import Execution, run_plan
from ..executor.dispatch import dispatch_plan, load_dispatch
from ..files import check_output_file, read_json, write_json
from ..plan_language import read_plan
from ..robots import parse_robot_ids
from ..scoring import parse_goals, score_execution
from ..tasks import find_task, load_tasks
from ..world.scenes import floor_plan_name, load_scene

DOMAIN_HELP = "The domain: household (the default), patrol, or a domain folder (see `smartllm-local domain`)."
CATALOGUE_HELP = "A JSON robot catalogue to use instead of an AI2-THOR domain's robots (default: the domain's own)."
THOR_BUILD_HELP = "A Unity AI2-THOR executable to run in (default: $SMARTLLM_THOR_BUILD, else the headless stand-in)."


def validate(
    plan: Path = typer.Argument(..., help="The plan file (.py)."),
    stage: str = typer.Option("allocated", help="decomposed (no robot arguments) or allocated."),
    floor_plan: str | None = typer.Option(None, help="Also check object names against this floor plan."),
    robots: str | None = typer.Option(None, help="Also check robots[i] against this team (catalogue ids, e.g. 1,2,3)."),
    catalogue: Path | None = typer.Option(None, help=CATALOGUE_HELP),
    domain: str | None = typer.Option(None, help=DOMAIN_HELP),
) -> None:
    """Parse and validate a plan without running it."""
    if stage not in ("decomposed", "allocated"):
        raise UserError(f"--stage must be decomposed or allocated, not {stage!r}")
    dom = load_domain(domain, catalogue=catalogue)
    cat = dom.catalogue
    team_size = len(cat.team(parse_robot_ids(robots))) if robots else None
    if not dom.is_ai2thor:
        if floor_plan:
            raise UserError(f"--floor-plan is for the household domain; the {dom.name} domain's plans are checked "
                            f"against its site {dom.site}")
        scene_types: set[str] | None = set(dom.places)
    else:
        scene_types = {o["objectType"] for o in load_scene(floor_plan_name(floor_plan))} if floor_plan else None
    parsed = read_plan(plan, form=stage, skills=cat.skills, team_size=team_size, scene_types=scene_types)  # type: ignore[arg-type]
    if parsed.is_refusal:
        typer.echo(f"{plan}: valid refusal: {parsed.refusal}")
        return
    subtasks = [f for f in parsed.functions]
    typer.echo(
        f"{plan}: valid {stage} plan: {len(subtasks)} function(s), {len(parsed.skill_calls())} skill call(s), "
        f"stages {parsed.stages()}"
    )


def refuse_household_options(dom: Domain, floor_plan: str | None, thor_build: Path | None) -> None:
    """A site domain's plans run on its site: AI2-THOR's floor plan and build options do not apply."""
    if not dom.is_ai2thor and (floor_plan or thor_build):
        raise UserError(f"--floor-plan and --thor-build are for the household domain; the {dom.name} domain's "
                        f"plans run on its site {dom.site}")


def check_transitions(trans: int | None, max_trans: int | None) -> None:
    """RU (and so SR) needs both the ground-truth and the maximum transitions, 0 <= trans <= max_trans."""
    for name, value in (("--trans", trans), ("--max-trans", max_trans)):
        if value is not None and value < 0:
            raise UserError(f"{name} must be 0 or more, not {value}")
    if (trans is None) != (max_trans is None):
        given, missing = ("--trans", "--max-trans") if max_trans is None else ("--max-trans", "--trans")
        raise UserError(f"{given} needs {missing} too: RU and SR are scored from both")
    if trans is not None and max_trans is not None and max_trans < trans:
        raise UserError(f"--max-trans ({max_trans}) must be at least --trans ({trans})")


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
    trace: Path | None = typer.Option(None, help="Write every primitive action to this JSON file."),
    catalogue: Path | None = typer.Option(None, help=CATALOGUE_HELP),
    thor_build: Path | None = typer.Option(None, help=THOR_BUILD_HELP),
    domain: str | None = typer.Option(None, help=DOMAIN_HELP),
) -> None:
    """Run a plan with a robot team (in AI2-THOR, or on a site domain's site) and print SR, TCR, GCR, RU and Exe."""
    given_transitions = trans is not None or max_trans is not None
    if trace is not None:
        check_output_file(trace, "--trace")
    dom = load_domain(domain, catalogue=catalogue)
    cat = dom.catalogue
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
        if not ((floor_plan or not dom.is_ai2thor) and robots and goal):
            raise UserError("execute needs --floor-plan, --robots and --goal (or --task ID)" if dom.is_ai2thor
                            else "execute needs --robots and --goal (or --task ID)")
        scene = floor_plan_name(floor_plan) if dom.is_ai2thor else dom.site
        team_ids = parse_robot_ids(robots)
        goals = list(parse_goals(read_json(goal, "goal file"), where=str(goal), states=dom.states))
        if not goals:
            raise UserError(f"goal file {goal}: a goal file needs at least one condition, "
                            'e.g. [{"name": "Fridge", "contains": ["Apple"], "state": null}]')
    if given_transitions:
        check_transitions(trans, max_trans)
    team = cat.team(team_ids)
    parsed = read_plan(plan, form="allocated", skills=cat.skills, team_size=len(team),
                       scene_types=None if dom.is_ai2thor else set(dom.places))
    execution = run_plan(parsed, scene, team, build=str(thor_build) if thor_build else None, skills=cat.skills,
                         site=dom.as_site)
    scores = score_execution(execution, goals, trans=trans, max_trans=max_trans)
    if trace is not None:
        write_json(trace, {"plan": str(plan), "floor_plan": scene, "robots": team_ids, **run_record(execution)})
    if as_json:
        typer.echo(json.dumps(scores.metrics()))
        return
    fmt = lambda v: "n/a" if v is None else f"{v:.2f}"  # noqa: E731
    typer.echo(f"{plan} on {scene} with robots {team_ids}: {execution.succeeded}/{execution.attempted} actions "
               f"succeeded in {execution.ticks} ticks, {execution.transitions} transition(s)")
    for entry in execution.trace:
        if not entry.success:
            typer.echo(f"  tick {entry.tick}: {entry.skill}{tuple(entry.objects)} by {entry.robots} "
                       f"failed: {entry.error}")
    for description, ok in scores.conditions:
        typer.echo(f"  [{'x' if ok else ' '}] {description}")
    typer.echo(f"SR {fmt(scores.SR)}  TCR {fmt(scores.TCR)}  GCR {fmt(scores.GCR)}  "
               f"RU {fmt(scores.RU)}  Exe {fmt(scores.Exe)}")


def dispatch(
    plan: Path = typer.Argument(..., help="The allocated plan file (.py)."),
    functions: Path = typer.Argument(..., help="The dispatch file (TOML): the module:function carrying out "
                                               "each skill."),
    robots: str = typer.Option(..., help="The team as catalogue ids, e.g. 1,2,3; robots[i] is the i-th."),
    trace: Path | None = typer.Option(None, help="Write every action to this JSON file."),
    catalogue: Path | None = typer.Option(None, help=CATALOGUE_HELP),
    domain: str | None = typer.Option(None, help=DOMAIN_HELP),
) -> None:
    """Run a plan on real robots: each skill call goes to the lab's own function for that skill.

    Exits 0 when every action succeeded, 1 when one failed (raised, returned False or timed out)."""
    if trace is not None:
        check_output_file(trace, "--trace")
    cat = load_domain(domain, catalogue=catalogue).catalogue
    team_ids = parse_robot_ids(robots)
    team = cat.team(team_ids)
    parsed = read_plan(plan, form="allocated", skills=cat.skills, team_size=len(team))
    execution = dispatch_plan(parsed, team, load_dispatch(functions, cat.skills), skills=cat.skills)
    if trace is not None:
        write_json(trace, {"plan": str(plan), "dispatch": str(functions), "robots": team_ids,
                           **run_record(execution)})
    typer.echo(f"{plan} with robots {team_ids}: " + "\n".join(dispatch_report(execution)))
    if not dispatch_succeeded(execution):
        raise typer.Exit(1)


def run_record(execution: Execution) -> dict[str, Any]:
    """A run's structure and every action, as ``--trace`` files and ``plan --json`` write them."""
    return {"transitions": execution.transitions, "ticks": execution.ticks,
            "actions": [e.as_dict() for e in execution.trace]}


def dispatch_report(execution: Execution) -> list[str]:
    """How a dispatched run went: a summary line, then each failed action."""
    return [f"{execution.succeeded}/{execution.attempted} actions succeeded in {execution.ticks} ticks, "
            f"{execution.transitions} transition(s)"] + [
        f"  tick {e.tick}: {e.skill}{tuple(e.objects)} by {e.robots} failed: {e.error}"
        for e in execution.trace if not e.success]


def dispatch_succeeded(execution: Execution) -> bool:
    return execution.succeeded == execution.attempted and not execution.truncated
