"""``smartllm-local dispatch``: run an allocated plan file on a lab's robots, each skill call going to the
lab's own function; and how a dispatched run is reported (``plan --dispatch`` too)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer

from ..domain import load_domain
from ..executor import Execution
from ..executor.dispatch import dispatch_plan, load_dispatch
from ..files import check_output_file, write_json
from ..plan_language import read_plan
from ..robots import parse_robot_ids
from ..worlds import with_catalogue
from .options import CATALOGUE_HELP, DOMAIN_HELP, given_path


def dispatch(
    plan: Path = typer.Argument(..., help="The allocated plan file (.py)."),
    functions: Path = typer.Argument(..., help="The dispatch file (TOML): the module:function carrying out "
                                               "each skill."),
    robots: str = typer.Option(..., help="The team as catalogue ids, e.g. 1,2,3; robots[i] is the i-th."),
    trace: Path | None = typer.Option(None, parser=given_path, metavar="FILE",
                                      help="Write every action to this JSON file."),
    catalogue: Path | None = typer.Option(None, help=CATALOGUE_HELP),
    domain: str | None = typer.Option(None, help=DOMAIN_HELP),
) -> None:
    """Run a plan on real robots: each skill call goes to the lab's own function for that skill.

    Exits 0 when every action succeeded, 1 when one failed (raised, returned False or timed out)."""
    if trace is not None:
        check_output_file(trace, "--trace")
    cat = with_catalogue(load_domain(domain), catalogue).catalogue
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
