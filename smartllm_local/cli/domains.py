"""``smartllm-local domain``: list the built-in domains, start a domain of your own, check one."""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

import typer

from ..domain import BENCHMARK, DOMAIN_FILE, PROMPTS, builtin_domains, load_domain, starter_domain
from ..errors import UserError

app = typer.Typer(help="Domains: your own robots, skills and site (see docs/domains.md).",
                  no_args_is_help=True)


@app.command("list")
def list_domains() -> None:
    """Print the built-in domains with their robots and skills."""
    for name in builtin_domains():
        domain = load_domain(name)
        typer.echo(f"{name:<12}{len(domain.catalogue.robots):>3} robots, {len(domain.catalogue.skills):>2} skills  "
                   f"{domain.description}")


@app.command("new")
def new(folder: Path = typer.Argument(..., help="The folder to create (it must not exist yet)."),
        source: str | None = typer.Option(None, "--from", help=(
            "Copy a built-in domain instead of the starter site: household, for your own robots or skills in "
            "AI2-THOR; patrol."))) -> None:
    """Write a commented starting domain (domain.toml, prompt examples, a task and its reference plan) to edit
    into your own, or a copy of a built-in domain."""
    if source is not None and source not in builtin_domains():
        raise UserError(f"--from takes a built-in domain ({', '.join(builtin_domains())}), not {source!r}")
    if folder.exists():
        raise UserError(f"{folder} already exists: `domain new` writes a new folder, so give one that does not exist")
    if not folder.parent.is_dir():
        raise UserError(f"{folder.parent} is not a folder: create it first, or give a folder inside an existing one")
    # Copied beside the target, then renamed into place: an interrupted copy leaves no half-made domain.
    staging = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", dir=folder.parent))
    staging.chmod(0o755)  # mkdtemp's folder is private; a domain folder is not
    try:
        origin = starter_domain() if source is None else load_domain(source).folder
        shutil.copytree(origin, staging, dirs_exist_ok=True, ignore=shutil.ignore_patterns("__pycache__"))
        os.replace(staging, folder)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    typer.echo(f"wrote {folder}/{DOMAIN_FILE}, {PROMPTS}/ (prompt examples) and {BENCHMARK}/ (its tasks and "
               f"reference_plans/): edit them, then run `smartllm-local domain check {folder}`")


@app.command("check")
def check(domain: str = typer.Argument(..., help="A domain folder, or a built-in domain's name.")) -> None:
    """Check a domain: its file, its prompt examples (each in its stage's grammar), its tasks and its reference
    plans (run in its world), and its development/test split if it has one. Exit 2 for a problem in a file (a
    feasible task in neither half of the split too), 1 if a reference plan falls short."""
    from ..benchmark.reference_plans import category_table, check_reference_plans
    from ..benchmark.tasks import load_tasks
    from ..planner.prompting.example_check import check_examples
    from ..worlds import world_of
    from .benchmark import check_split

    loaded = load_domain(domain)
    catalogue = loaded.catalogue
    count, problems = check_examples(loaded)
    if problems:
        raise UserError("\n".join(problems))
    typer.echo(f"{loaded.name}: {len(catalogue.skills)} skills, {len(catalogue.robots)} robots, "
               f"{world_of(loaded).describe_world()}, {count} prompt examples in their grammars")
    files = [f for f in loaded.task_files() if f.is_file()]
    if not files:
        typer.echo(f"no tasks: add {loaded.task_files()[0]} to benchmark it")
        return
    tasks = load_tasks(files, domain=loaded)
    results = check_reference_plans(tasks, domain=loaded)
    typer.echo(category_table(results))
    failed = [r for r in results if not r.passed]
    for result in failed:
        typer.echo(f"FAILED {result.task.id}: {result.problem}")
    check_split(loaded, tasks)
    if failed:
        raise typer.Exit(1)
