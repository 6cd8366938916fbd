"""``smartllm-local benchmark``: list the tasks, check the benchmark, report on runs, import task files."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from ..domain import load_domain
from ..files import check_output_file, write_atomic
from ..tasks import CATEGORIES, check_category, load_tasks
from .plans import DOMAIN_HELP

app = typer.Typer(help="The benchmark: list its tasks, check it, import SMART-LLM's task files.", no_args_is_help=True)


@app.command("list")
def list_tasks(
    category: str | None = typer.Option(None, help=f"Only this category: {', '.join(CATEGORIES)}."),
    tasks: Path | None = typer.Option(None, help="A task file (default: the domain's benchmark)."),
    as_json: bool = typer.Option(False, "--json", help="Print the tasks as JSON lines."),
    domain: str | None = typer.Option(None, help=DOMAIN_HELP),
) -> None:
    """Print the tasks: id, category, floor plan (or site), robots and instruction."""
    check_category(category)
    dom = load_domain(domain)
    chosen = [t for t in load_tasks(tasks or dom.task_files(), domain=dom) if category in (None, t.category)]
    if as_json:
        for task in chosen:
            typer.echo(json.dumps(task.as_json()))
        return
    rows = [(task.id, task.category, task.floor_plan, str(list(task.robots)),
             task.instruction + ("" if task.feasible else "  [infeasible]")) for task in chosen]
    # Each column as wide as its longest cell (at least as before), two spaces apart.
    widths = [max([minimum - 2, *(len(row[k]) for row in rows)]) for k, minimum in enumerate((16, 12, 14, 16))]
    for row in rows:
        typer.echo("".join(f"{cell:<{width + 2}}" for cell, width in zip(row, widths)) + row[-1])


@app.command("check")
def check(
    tasks: Path | None = typer.Option(None, help="A task file (default: the domain's benchmark)."),
    plans: Path | None = typer.Option(None, help="Reference plans folder (default: the domain's "
                                                 "benchmark/reference_plans)."),
    thor_build: Path | None = typer.Option(None, help="A Unity AI2-THOR executable (default: the stand-in)."),
    domain: str | None = typer.Option(None, help=DOMAIN_HELP),
) -> None:
    """Validate the task files and run every reference plan; print a per-category table."""
    from ..benchmark import category_table, check_reference_plans

    dom = load_domain(domain)
    loaded = load_tasks(tasks or dom.task_files(), domain=dom)
    results = check_reference_plans(loaded, plans, build=str(thor_build) if thor_build else None, domain=dom)
    typer.echo(category_table(results))
    failed = [r for r in results if not r.passed]
    for result in failed:
        typer.echo(f"FAILED {result.task.id}: {result.problem}")
    if failed:
        raise typer.Exit(1)


@app.command("report")
def report(
    runs: list[Path] = typer.Argument(..., help="Run folders (the --out of `benchmark run`; a --seeds folder is one "
                                                "row with its spread)."),
    out: Path | None = typer.Option(None, "--out", help="Where to write report.md, the CSVs and the figures "
                                                           "(default: FIRST_RUN/report)."),
) -> None:
    """The paper's Tables I-III, refusals, efficiency, time and tokens per stage (Markdown and CSV) and
    figures (PNG), from the runs' results.jsonl and run.json alone."""
    from ..report import write_report

    written = write_report(runs, out if out is not None else runs[0] / "report")
    typer.echo(written[0].read_text(encoding="utf-8"))
    typer.echo(f"wrote {', '.join(str(p) for p in written)}")


@app.command("import-smartllm")
def import_smartllm(
    source: Path = typer.Argument(..., help="SMART-LLM's repository (or its data/final_test folder)."),
    out: Path = typer.Option(..., "--out", help="The task file (JSON lines) to write."),
) -> None:
    """Import SMART-LLM's data/final_test/FloorPlan<N>.json files as a task file."""
    from ..importer import import_smartllm as run_import

    check_output_file(out, "--out")
    report = run_import(source)
    for note in report.notes:
        typer.echo(str(note))
    write_atomic(out, "".join(json.dumps(task) + "\n" for task in report.tasks))
    typer.echo(f"wrote {len(report.tasks)} task(s) to {out} ({report.summary()})")
