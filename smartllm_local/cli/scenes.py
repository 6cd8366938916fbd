"""``smartllm-local scenes``: the 120 iTHOR floor plans and their objects."""

from __future__ import annotations

import json
from dataclasses import asdict

import typer

from ..errors import UserError
from ..world.scenes import ROOM_BLOCKS, all_floor_plans, load_scene, scene_info, summarize_scene

app = typer.Typer(help="List the iTHOR floor plans and show their objects.", no_args_is_help=True)


@app.command("list")
def list_scenes(
    room: str = typer.Option(None, help="Only this room type: kitchen, 'living room', bedroom, bathroom."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON lines instead of a table."),
) -> None:
    """Floor plans with their room type and object count."""
    wanted = None
    if room is not None:
        wanted = " ".join(room.replace("_", " ").lower().split())
        room_types = [room_type for _, _, room_type in ROOM_BLOCKS]
        if wanted not in room_types:
            raise UserError(f"--room must be one of {', '.join(repr(r) for r in room_types)}, not {room!r}")
    rows = []
    for name in all_floor_plans():
        info = scene_info(name)
        if wanted is not None and info.room_type != wanted:
            continue
        objects = load_scene(name)
        rows.append({"floor_plan": name, "room_type": info.room_type, "objects": len(objects),
                     "types": len({o["objectType"] for o in objects})})
    if as_json:
        for row in rows:
            typer.echo(json.dumps(row))
        return
    typer.echo(f"{'floor plan':<14}{'room':<13}{'objects':>8}{'types':>7}")
    for row in rows:
        typer.echo(f"{row['floor_plan']:<14}{row['room_type']:<13}{row['objects']:>8}{row['types']:>7}")


@app.command("show")
def show_scene(
    floor_plan: str = typer.Argument(..., help="FloorPlan6, or just 6."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a table."),
) -> None:
    """The object types of a floor plan: count, mass (kg, heaviest instance) and properties."""
    info = scene_info(floor_plan)
    summary = summarize_scene(info.name)
    if as_json:
        typer.echo(json.dumps({"floor_plan": info.name, "room_type": info.room_type,
                               "types": [asdict(t) for t in summary]}, indent=2))
        return
    typer.echo(f"{info.name} ({info.room_type}): {sum(t.count for t in summary)} objects, {len(summary)} types")
    typer.echo(f"{'type':<20}{'count':>6}{'mass kg':>9}  properties")
    for t in summary:
        typer.echo(f"{t.object_type:<20}{t.count:>6}{t.mass:>9.3f}  {', '.join(t.properties) or '-'}")
