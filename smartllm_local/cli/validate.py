"""``smartllm-local validate``: parse and check a plan file without running it."""

from __future__ import annotations

from pathlib import Path

import typer

from ..domain import load_domain
from ..errors import UserError
from ..plan_language import read_plan
from ..robots import parse_robot_ids
from ..worlds import with_catalogue, world_of
from .options import CATALOGUE_HELP, DOMAIN_HELP


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
    dom = with_catalogue(load_domain(domain), catalogue)
    cat = dom.catalogue
    team_size = len(cat.team(parse_robot_ids(robots))) if robots else None
    world = world_of(dom)
    floor_plans = "--floor-plan" in world.options  # else every plan is for the world's one place
    if floor_plan and not floor_plans:
        raise UserError(f"--floor-plan is for the household domain; the {dom.name} domain's plans are checked "
                        f"against {world.venue}")
    scene_types = world.scene(world.scene_name(floor_plan)).types if floor_plan or not floor_plans else None
    parsed = read_plan(plan, form=stage, skills=cat.skills, team_size=team_size, scene_types=scene_types)  # type: ignore[arg-type]
    if parsed.is_refusal:
        typer.echo(f"{plan}: valid refusal: {parsed.refusal}")
        return
    subtasks = [f for f in parsed.functions]
    typer.echo(
        f"{plan}: valid {stage} plan: {len(subtasks)} function(s), {len(parsed.skill_calls())} skill call(s), "
        f"stages {parsed.stages()}"
    )
