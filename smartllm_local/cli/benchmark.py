"""``smartllm-local benchmark``: run it (plan, execute and score every task, resumable), list its tasks, check
its reference plans, report on runs, import task files."""

from __future__ import annotations

import json
import sys
from dataclasses import asdict
from pathlib import Path
from typing import Any

import typer

from ..benchmark.methods import METHODS, MODEL_FREE, check_time_limit, make_method
from ..benchmark.results import summary_table, variability_table
from ..benchmark.run import run_benchmark
from ..benchmark.run_store import RunStore
from ..benchmark.split import (
    Split,
    check_half,
    domain_split,
    require_split,
    split_problems,
    split_summary,
    split_tasks,
)
from ..benchmark.tasks import CATEGORIES, Task, check_category, find_task, load_tasks
from ..domain import Domain, load_domain
from ..errors import UserError
from ..files import check_output_file, check_output_folder, write_atomic
from ..planner.backends import model_location
from ..planner.pipeline import Planner
from ..provenance import run_manifest
from ..world.controller import check_build
from ..worlds import with_catalogue, world_of
from .options import (
    CATALOGUE,
    DOMAIN,
    DOMAIN_HELP,
    MAX_SEED,
    PLANNER_TIME_LIMIT,
    READ_STEPS,
    TASKS,
    THOR_BUILD,
    ModelOptions,
    given_path,
    model_options,
    refuse_household_options,
)
from .progress import RunProgress

SPLIT_HELP = ("Only this half of the domain's development/test split (benchmark/split.toml): dev or test, "
              "each with every infeasible task (default: every task).")

app = typer.Typer(help="The benchmark: run it, list its tasks, check it, report on runs, import SMART-LLM's task "
                       "files.",
                  no_args_is_help=True)


@app.command("list")
def list_tasks(
    category: str | None = typer.Option(None, help=f"Only this category: {', '.join(CATEGORIES)}."),
    tasks: Path | None = typer.Option(None, help="A task file (default: the domain's benchmark)."),
    as_json: bool = typer.Option(False, "--json", help="Print the tasks as JSON lines."),
    domain: str | None = typer.Option(None, help=DOMAIN_HELP),
    split: str | None = typer.Option(None, metavar="dev|test", help=SPLIT_HELP),
) -> None:
    """Print the tasks: id, category, floor plan (or site), robots and instruction."""
    check_category(category)
    dom = load_domain(domain)
    chosen = [t for t in _load(dom, tasks, split)[1] if category in (None, t.category)]
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
    from ..benchmark.reference_plans import category_table, check_reference_plans

    dom = load_domain(domain)
    loaded = load_tasks(tasks or dom.task_files(), domain=dom)
    if plans is not None and not plans.is_dir():
        raise UserError(f"--plans {plans} is not a folder: give the folder of reference plans (<task id>.py)")
    refuse_household_options(dom, None, thor_build)
    if "--thor-build" in world_of(dom).options:
        check_build(thor_build)
    results = check_reference_plans(loaded, plans, build=str(thor_build) if thor_build else None, domain=dom)
    typer.echo(category_table(results))
    failed = [r for r in results if not r.passed]
    for result in failed:
        typer.echo(f"FAILED {result.task.id}: {result.problem}")
    if tasks is None:  # the split is of the domain's own tasks
        check_split(dom, loaded)
    if failed:
        raise typer.Exit(1)


def check_split(dom: Domain, tasks: list[Task]) -> None:
    """Print the domain's split, if it has one.

    Raises:
        UserError: the split does not fit ``tasks`` (every problem named).
    """
    split = domain_split(dom)
    if split is None:
        return
    typer.echo(split_summary(split, tasks))
    problems = split_problems(split, tasks)
    if problems:
        raise UserError("\n".join(problems))


@app.command("report")
def report(
    runs: list[Path] = typer.Argument(..., help="Run folders (the --out of `benchmark run`; a --seeds folder is one "
                                                "row with its spread)."),
    out: Path | None = typer.Option(None, "--out", parser=given_path, metavar="DIR", help=(
        "Where to write report.md, the CSVs and the figures (default: FIRST_RUN/report).")),
    html: bool = typer.Option(False, "--html", help=(
        "Also write each run's viewer page (as `smartllm-local view` does; one per seed) and link it from "
        "report.md.")),
) -> None:
    """The paper's Tables I-III, refusals, efficiency, time and tokens per stage (Markdown and CSV) and
    figures (PNG), from the runs' results.jsonl and run.json alone."""
    from ..report import write_report

    folders = [run.resolve() for run in runs]
    twice = sorted({str(run) for run, folder in zip(runs, folders) if folders.count(folder) > 1})
    if twice:
        raise UserError(f"{', '.join(twice)}: a run folder given more than once would be a row of the report twice")
    written = write_report(runs, out if out is not None else runs[0] / "report", html=html)
    typer.echo(written[0].read_text(encoding="utf-8"))
    typer.echo(f"wrote {', '.join(str(p) for p in written)}")


@app.command("import-smartllm")
def import_smartllm(
    source: Path = typer.Argument(..., help="SMART-LLM's repository (or its data/final_test folder)."),
    out: Path = typer.Option(..., "--out", parser=given_path, metavar="FILE",
                             help="The task file (JSON lines) to write."),
) -> None:
    """Import SMART-LLM's data/final_test/FloorPlan<N>.json files as a task file."""
    from ..benchmark.importer import import_smartllm as run_import

    check_output_file(out, "--out")
    report = run_import(source)
    for note in report.notes:
        typer.echo(str(note))
    write_atomic(out, "".join(json.dumps(task) + "\n" for task in report.tasks))
    typer.echo(f"wrote {len(report.tasks)} task(s) to {out} ({report.summary()})")


@app.command("run")
@model_options()
def run(
    ctx: typer.Context,
    out: Path = typer.Option(..., "--out", parser=given_path, metavar="DIR", help=(
        "Folder for run.json, per-task artifacts, results.jsonl and summary.txt. A run stopped at any "
        "point (Ctrl-C, a crash, kill -9) and started again with the same arguments resumes here.")),
    restart: bool = typer.Option(False, "--restart", help="Discard the run --out holds and start over."),
    seeds: str | None = typer.Option(None, "--seeds", help=(
        "N (seeds --seed … --seed+N-1) or a list (0,3,7): every task once per seed (with --temperature "
        "above 0), each run in DIR/seed-<s>/; summary.txt gives each category's mean ± standard deviation "
        "over the seeds (the paper's Table II).")),
    method: str = typer.Option("smartllm", help=(
        f"{', '.join(METHODS)}: SMART-LLM's stages; the model's decomposition with robots at random (seeded) "
        "or by a rule (a capable robot, else the smallest capable team); the model states the goal and Fast "
        "Downward finds the steps; the same with the task's own goal conditions "
        "as the goal (an oracle: no model); the reference plans (no model).")),
    planner_time_limit: float = PLANNER_TIME_LIMIT,
    read_steps: bool = READ_STEPS,
    tasks: Path | None = TASKS,
    category: str | None = typer.Option(None, help=f"Only this category: {', '.join(CATEGORIES)}."),
    task: list[str] | None = typer.Option(None, help="Only these task ids (repeatable)."),
    split: str | None = typer.Option(None, metavar="dev|test", help=SPLIT_HELP),
    catalogue: Path | None = CATALOGUE,
    thor_build: Path | None = THOR_BUILD,
    domain: str | None = DOMAIN,
    *,
    model_settings: dict[str, Any],
) -> None:
    """Plan, execute and score every task of a task file; print a per-category table."""
    options = ModelOptions(**model_settings)
    check_output_folder(out, "--out")
    dom = with_catalogue(load_domain(domain), catalogue)
    tasks_files = [tasks] if tasks else dom.task_files()
    loaded, half, found = _load(dom, tasks, split)
    chosen = _chosen_tasks(half, found, category, task, split)
    _check_run(dom, loaded, found, method=method, split=split, thor_build=thor_build,
               planner_time_limit=planner_time_limit)
    chosen_seeds = parse_seeds(seeds, options.seed)
    if len(chosen_seeds) > 1 and options.config.sampling.temperature == 0 and method != "decomp-random":
        raise UserError("--seeds needs --temperature above 0: greedy decoding writes the same plans for every seed")
    runs = _open_runs(ctx.params, options, dom, out, chosen_seeds, tasks_files=tasks_files, method=method, found=found,
                      by_seed=seeds is not None, restart=restart)
    _run_seeds(runs, chosen, options, method, dom, thor_build, labelled=seeds is not None,
               planner_time_limit=planner_time_limit, read_steps=read_steps)
    _print_summary(runs, chosen, out, by_seed=seeds is not None, split=split, found=found)


def _check_run(dom: Domain, loaded: list[Task], found: Split | None, *, method: str, split: str | None,
               thor_build: Path | None, planner_time_limit: float) -> None:
    """Check the method, its time limit and the world's build before anything is written or loaded; warn (and go
    on) where a run of every task finds the domain's split does not fit its tasks."""
    if method not in METHODS:
        raise UserError(f"--method must be one of {', '.join(METHODS)}, not {method!r}")
    if method.startswith("goal-planner"):
        check_time_limit(planner_time_limit)
    problems = split_problems(found, loaded) if found is not None and split is None else []
    if problems:  # a run of every task goes on, and records the split as it is for the report
        print("warning: " + "\nwarning: ".join(problems) + "\nwarning: the report's test-half rows go by the split "
              "as it is (`benchmark check` lists the same)", file=sys.stderr)
    refuse_household_options(dom, None, thor_build)
    if "--thor-build" in world_of(dom).options:
        check_build(thor_build)  # every task runs in it


def _open_runs(params: dict[str, Any], options: ModelOptions, dom: Domain, out: Path, seeds: list[int], *,
               tasks_files: list[Path], method: str, found: Split | None, by_seed: bool,
               restart: bool) -> list[tuple[int, RunStore]]:
    """A run folder per seed (``out`` itself for one run without ``--seeds``), each with its manifest: every
    folder is checked (a run of other arguments there is refused) before the model loads."""
    arguments = {k: v for k, v in params.items()
                 if k not in ("out", "restart", "seeds", "prefix_cache", "parallel", "server_timeout")}
    arguments["n_ctx"] = options.n_ctx  # the context asked for, given or not, as run.json has always named it
    model_path = None if method in MODEL_FREE else model_location(options.backend, options.model)
    runs = []
    for s in seeds:
        folder = out / f"seed-{s}" if by_seed else out
        manifest = run_manifest({**arguments, "seed": s}, model_path, asdict(options.config_for(s)), tasks_files,
                                Path(dom.catalogue.path), dom.prompts_dir(),
                                split=found.record() if found is not None else None)
        runs.append((s, RunStore(folder, manifest, restart=restart)))
    return runs


def _print_summary(runs: list[tuple[int, RunStore]], chosen: list[Task], out: Path, *, by_seed: bool,
                   split: str | None, found: Split | None) -> None:
    """Print the per-category table of the run (each category's mean and spread over the seeds with ``--seeds``,
    written to summary.txt too) and where the results are."""
    per_run = [[lines[t.id] for t in chosen if t.id in lines] for lines in (store.results() for _, store in runs)]
    if split is not None and found is not None:
        typer.echo(f"the {split} half of {found.path} (seed {found.seed}), and every infeasible task:")
    if not by_seed:
        typer.echo(summary_table(per_run[0]))
        typer.echo(f"results: {out / 'results.jsonl'}")
        return
    table = variability_table(per_run)
    write_atomic(out / "summary.txt", table + "\n")
    typer.echo(table)
    typer.echo(f"results: {', '.join(str(store.out / 'results.jsonl') for _, store in runs)}")


def _load(dom: Domain, tasks: Path | None, split: str | None) -> tuple[list[Task], list[Task], Split | None]:
    """The tasks of ``--tasks`` (default: the domain's task files); those of the ``--split`` half (all of them
    without one); and the domain's split where the tasks are its own (None for a ``--tasks`` file or a domain
    without one)."""
    if split is not None:
        check_half(split)
        if tasks is not None:
            raise UserError(f"--split takes a half of the {dom.name} domain's own benchmark: leave out --tasks, "
                            "or --split to take every task of the file")
    loaded = load_tasks(tasks or dom.task_files(), catalogue=dom.catalogue, domain=dom)
    if tasks is not None:
        return loaded, loaded, None
    if split is None:
        return loaded, loaded, domain_split(dom)
    found = require_split(dom)
    return loaded, split_tasks(loaded, found, split), found


def _chosen_tasks(half: list[Task], found: Split | None, category: str | None, ids: list[str] | None,
                  split: str | None) -> list[Task]:
    """The tasks (of the ``--split`` half) that pass ``--category`` and ``--task``; none is an error, and so is
    a ``--task`` of the other half."""
    check_category(category)
    chosen = [t for t in half if category in (None, t.category)]
    if ids:
        halves = found.halves if found is not None and split is not None else {}
        for task_id in ids:
            if halves.get(task_id, split) != split:
                raise UserError(f"task {task_id!r} is in the {halves[task_id]} half, not in --split {split}")
        twice = sorted({t for t in ids if ids.count(t) > 1})
        if twice:
            raise UserError(f"--task {', '.join(twice)} is given more than once: each task is run once per seed")
        chosen = [find_task(chosen, t) for t in ids]
    if not chosen:
        raise UserError("no task matches the filters")
    return chosen


def _run_seeds(runs: list[tuple[int, RunStore]], chosen: list[Task], options: ModelOptions, method: str,
               dom: Domain, thor_build: Path | None, *, labelled: bool, planner_time_limit: float,
               read_steps: bool) -> None:
    """Plan, execute and score the tasks once per seed, resuming each run; Ctrl-C says how far it got."""
    cat = dom.catalogue
    planner_set = None if method in MODEL_FREE else options.open_planners(cat, dom, len(chosen))
    planners = planner_set.planners if planner_set is not None else []
    try:
        for s, store in runs:
            done = store.results()
            if done:
                print(f"resuming the run in {store.out}: {sum(t.id in done for t in chosen)} of {len(chosen)} "
                      "tasks done", file=sys.stderr)
            seeded = [Planner(p.backend, cat, options.config_for(s), p.examples, p.world) for p in planners] or [None]
            with RunProgress(f"seed {s}" if labelled else "") as progress:
                methods = [make_method(method, cat, p, dom.plans_dir(), planner_time_limit=planner_time_limit,
                                       world=world_of(dom), read_steps=read_steps) for p in seeded]
                run_benchmark(chosen, methods, cat,
                              out=store.out, store=store, build=str(thor_build) if thor_build else None,
                              progress=progress, domain=dom,
                              interrupt=planner_set.interrupt if planner_set is not None else lambda: None)
    except KeyboardInterrupt:
        scored = sum(t.id in store.results() for _, store in runs for t in chosen)
        print(f"interrupted: {scored} of {len(chosen) * len(runs)} tasks scored; the same command resumes the run",
              file=sys.stderr)
        raise typer.Exit(130) from None
    finally:
        if planner_set is not None:
            planner_set.close()


def parse_seeds(seeds: str | None, seed: int) -> list[int]:
    """``--seeds``: N (seeds ``seed`` .. ``seed + N - 1``) or a comma-separated list; none: ``[seed]``."""
    if seeds is None:
        return [seed]
    try:
        values = [int(v) for v in seeds.split(",")] if "," in seeds else list(range(seed, seed + int(seeds)))
    except ValueError:
        raise UserError(f"--seeds must be a count (e.g. 5) or a list of seeds (e.g. 0,1,2), not {seeds!r}") from None
    if not values or len(set(values)) != len(values) or not all(0 <= v <= MAX_SEED for v in values):
        raise UserError(f"--seeds must name distinct seeds between 0 and {MAX_SEED}, at least one, not {seeds!r}")
    return values
