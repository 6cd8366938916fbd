"""``smartllm-local plan`` and ``smartllm-local benchmark run``: the planner on a local model."""

from __future__ import annotations

import inspect
import json
import math
import sys
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

import typer

from ..domain import Domain, load_domain
from ..errors import UserError
from ..evaluation import execute_and_score, run_benchmark
from ..executor.dispatch import dispatch_plan, load_dispatch
from ..files import check_output_folder, write_atomic
from ..methods import METHODS, make_method
from ..planner.backends import (
    BACKENDS,
    Backend,
    LoopGuard,
    Sampling,
    check_server_options,
    load_backends,
    model_location,
)
from ..planner.chat import CHAT_TEMPLATE_MODES, mode_for
from ..planner.models import DEFAULT_MODEL, EMBEDDED, default_model
from ..planner.pipeline import Planner, PlannerConfig, write_artifacts
from ..planner.prefix_cache import open_store
from ..planner.prompts import PromptOptions
from ..provenance import run_manifest
from ..results import summary_table, variability_table
from ..robots import parse_robot_ids
from ..run_store import RunStore
from ..tasks import CATEGORIES, check_category, find_task, load_tasks
from ..world.scenes import floor_plan_name
from .plans import (
    CATALOGUE_HELP,
    DOMAIN_HELP,
    dispatch_report,
    dispatch_succeeded,
    refuse_household_options,
    run_record,
)
from .progress import RunProgress

MODEL_HELP = (f"A GGUF file (llama.cpp), a checkpoint folder or GGUF (transformers), or an embedded model: "
              f"{', '.join(EMBEDDED)} (default: {DEFAULT_MODEL}, or what SMARTLLM_MODEL names).")

MAX_SEED = 2**32 - 1  # llama.cpp takes an unsigned 32-bit seed


class ModelOptions:
    """The options every planning command shares, turned into a Planner."""

    def __init__(self, *, model: str | None = None, backend: str = "llamacpp", n_ctx: int = 8192,
                 threads: int | None = None, n_gpu_layers: int = 0, seed: int = 0, temperature: float = 0.0,
                 no_comments: bool = False, no_summary: bool = False, no_coalition: bool = False,
                 no_grammar: bool = False, free_teams: bool = False, chat_template: str = "auto",
                 free_allocation: bool = False, no_world_check: bool = False, prefix_cache: str | None = None,
                 endpoint: str | None = None, workers: int = 1, server_timeout: float | None = None,
                 no_loop_guard: bool = False, no_token_alignment: bool = False):
        if backend not in BACKENDS:
            raise UserError(f"--backend must be one of {', '.join(BACKENDS)}, not {backend!r}")
        if not math.isfinite(temperature) or temperature < 0:
            raise UserError(f"--temperature must be a number, 0 (greedy) or more, not {temperature}")
        if not 0 <= seed <= MAX_SEED:
            raise UserError(f"--seed must be between 0 and {MAX_SEED}, not {seed}")
        if n_ctx < 512:
            raise UserError("--n-ctx must be at least 512 tokens")
        chat_template = mode_for(model if backend == "server" else model or default_model(), chat_template)
        self.endpoints = [e.strip() for e in endpoint.split(",") if e.strip()] if endpoint else []
        check_server_options(backend, self.endpoints, workers)
        if server_timeout is not None and not (math.isfinite(server_timeout) and server_timeout > 0):
            raise UserError(f"--server-timeout must be a number of seconds above 0, not {server_timeout}")
        self.workers, self.server_timeout = workers, server_timeout
        self.model, self.backend, self.n_ctx, self.threads = model, backend, n_ctx, threads
        self.n_gpu_layers = n_gpu_layers
        self.prefix_cache = prefix_cache
        if backend == "llamacpp":  # a cache folder that can never be one fails before the model loads
            open_store(prefix_cache)
        self.config = PlannerConfig(
            sampling=Sampling(temperature=temperature, seed=seed, loop_guard=None if no_loop_guard else LoopGuard(),
                              aligned=not no_token_alignment),
            grammar=not no_grammar,
            free_teams=free_teams,
            prompts=PromptOptions(comments=not no_comments, summary=not no_summary, coalition=not no_coalition),
            chat_template=chat_template,
            restate=not free_allocation,
            world_check=not no_world_check,
        )
        self.seed = seed

    @classmethod
    def from_command(cls, arguments: dict[str, Any]) -> ModelOptions:
        """The options among a command's parameters (its ``locals()``), taken by name: a command lists them in
        whatever order reads best, and one it does not take keeps its default."""
        names = inspect.signature(cls).parameters
        return cls(**{name: value for name, value in arguments.items() if name in names})

    def config_for(self, seed: int) -> PlannerConfig:
        """The planner's settings with another sampling seed."""
        return replace(self.config, sampling=replace(self.config.sampling, seed=seed))

    def load(self, prefix_cache: str | None = None) -> Backend:
        """One backend for this model (a server's first slot), its prefix states in ``prefix_cache``."""
        return self._backends(1, prefix_cache)[0]

    def _backends(self, workers: int, prefix_cache: str | None) -> list[Backend]:
        return load_backends(self.backend, self.model, workers=workers, endpoints=self.endpoints,
                             server_timeout=self.server_timeout, n_ctx=self.n_ctx, threads=self.threads,
                             n_gpu_layers=self.n_gpu_layers, seed=self.seed, prefix_cache=prefix_cache)

    def as_arguments(self) -> list[str]:
        """The model's options as ``plan`` and ``benchmark run`` take them on the command line."""
        return [*(["--model", self.model] if self.model else []), "--backend", self.backend,
                *(["--endpoint", ",".join(self.endpoints)] if self.endpoints else []),
                *(["--server-timeout", str(self.server_timeout)] if self.server_timeout else []),
                "--n-ctx", str(self.n_ctx), "--n-gpu-layers", str(self.n_gpu_layers),
                "--chat-template", self.config.chat_template,
                *(["--threads", str(self.threads)] if self.threads else [])]

    def planners(self, catalogue, domain: Domain | None = None) -> list[Planner]:
        """One planner per worker (one, but for a server backend with --workers), for ``domain``'s tasks."""
        site = domain.as_site if domain is not None else None
        return [Planner(backend, catalogue, self.config, site=site)
                for backend in self._backends(self.workers, self.prefix_cache)]


# Options shared by every command that plans (typer option objects can be reused as defaults).
_MODEL = typer.Option(None, help=MODEL_HELP)
_BACKEND = typer.Option("llamacpp", help=(
    "llamacpp or transformers (the model runs in this process), or server (a llama-server, llama_cpp.server or "
    "vLLM at --endpoint runs it; --model then names the served GGUF or tokenizer folder, read for its vocabulary "
    "only)."))
_ENDPOINT = typer.Option(None, "--endpoint", metavar="URL[,URL...]", help=(
    "--backend server: the servers' URLs, such as http://gpu-box:8080 (llama-server, with -np slots) or "
    "http://127.0.0.1:8000 (python -m llama_cpp.server or vllm serve)."))
_SERVER_TIMEOUT = typer.Option(None, "--server-timeout", help=(
    "--backend server: seconds a request may go unanswered before its task fails (default 300)."))
_N_CTX = typer.Option(8192, "--n-ctx", help="Context size in tokens (at most the model's trained context).")
_THREADS = typer.Option(None, help="CPU threads (default: all cores).")
_GPU = typer.Option(0, "--n-gpu-layers", help="Layers to offload to a GPU (needs a CUDA or Metal build of llama.cpp).")
_SEED = typer.Option(0, help="Sampling seed.")
_TEMPERATURE = typer.Option(0.0, help="0 is greedy decoding.")
_NO_COMMENTS = typer.Option(False, "--no-comments", help="Ablation: examples without comments.")
_NO_SUMMARY = typer.Option(False, "--no-summary", help="Ablation: decompositions without the summary.")
_NO_COALITION = typer.Option(False, "--no-coalition", help="Ablation: skip coalition formation.")
_NO_GRAMMAR = typer.Option(False, "--no-grammar", help="Generate freely (for comparison); the output may be invalid.")
_FREE_TEAMS = typer.Option(False, "--free-teams", help="Let the model pick any team and refuse at will, rather than "
                                                       "only teams whose skills and strength suit each sub-task.")
_CHAT_TEMPLATE = typer.Option("auto", "--chat-template", help=(
    f"{' or '.join(CHAT_TEMPLATE_MODES)}. auto: a model whose file carries a chat template (an instruct "
    "model) gets each stage's prompt as the user turn and writes its output as the assistant turn; "
    "base models, and the embedded Qwen2.5-Coder models (measured better so), get raw text. on: the "
    "model's template wherever it has one. none: raw text for every model."))
_FREE_ALLOCATION = typer.Option(False, "--free-allocation", help=(
    "Let the allocation stage rewrite every step (as the paper's prompts allow), rather than write the "
    "decomposition's steps itself and leave the model only the robots and the orchestration."))
_NO_WORLD_CHECK = typer.Option(False, "--no-world-check", help=(
    "Offer steps whatever the scene's state, rather than only steps that succeed from the state the "
    "steps so far produce (for measuring the check's effect)."))
_NO_LOOP_GUARD = typer.Option(False, "--no-loop-guard", help=(
    "Let free text (summaries, comments, a coalition's reasoning) repeat itself to its length limit, rather "
    "than end it where it starts saying one thing a third time over (see docs/planner.md, \"Loops in free text\")."))
_NO_TOKEN_ALIGNMENT = typer.Option(False, "--no-token-alignment", help=(
    "Write text the grammar forces whole, end each line at its newline and let the model end only where the "
    "grammar may, rather than leave forced text's last token, line ends and the end of sequence to the model "
    "(for measuring what that changes; see docs/planner.md, \"Line ends and forced text\")."))
_PREFIX_CACHE = typer.Option(None, "--prefix-cache", metavar="DIR|off", help=(
    "Where the examples' key/value states are kept between runs, so a later run on the same model starts "
    "from them (default: the user's cache, $XDG_CACHE_HOME/smartllm-local/prefix-states, at most 4 GiB); "
    "off keeps them for this run only. llama.cpp only."))
_CATALOGUE = typer.Option(None, help=CATALOGUE_HELP)
_THOR_BUILD = typer.Option(None, help="A Unity AI2-THOR executable (default: the headless stand-in).")
_TASKS = typer.Option(None, help="A task file (default: the project's benchmark).")


def plan_command(
    instruction: str | None = typer.Argument(None, help="What the robots should do (or use --task)."),
    floor_plan: str | None = typer.Option(None, help="Floor plan, e.g. 15 or FloorPlan15."),
    robots: str | None = typer.Option(None, help="The team as catalogue ids, e.g. 1,2,3."),
    tasks: Path | None = _TASKS,
    task: str | None = typer.Option(None, help="Plan this task of --tasks, with its floor plan and robots."),
    out: Path | None = typer.Option(None, help="Write prompts, grammars, raw outputs and timings here."),
    execute: bool = typer.Option(False, "--execute", help="Run the plan in AI2-THOR and print the metrics."),
    dispatch: Path | None = typer.Option(None, "--dispatch", metavar="LAB.toml", help=(
        "Run the plan on the lab's robots: each skill call goes to the function this dispatch file names "
        "for it (see smartllm-local dispatch); exit 1 if an action failed.")),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
    catalogue: Path | None = _CATALOGUE,
    thor_build: Path | None = _THOR_BUILD,
    model: str | None = _MODEL,
    backend: str = _BACKEND,
    n_ctx: int = _N_CTX,
    threads: int | None = _THREADS,
    n_gpu_layers: int = _GPU,
    seed: int = _SEED,
    temperature: float = _TEMPERATURE,
    no_comments: bool = _NO_COMMENTS,
    no_summary: bool = _NO_SUMMARY,
    no_coalition: bool = _NO_COALITION,
    no_grammar: bool = _NO_GRAMMAR,
    free_teams: bool = _FREE_TEAMS,
    chat_template: str = _CHAT_TEMPLATE,
    free_allocation: bool = _FREE_ALLOCATION,
    no_world_check: bool = _NO_WORLD_CHECK,
    no_loop_guard: bool = _NO_LOOP_GUARD,
    no_token_alignment: bool = _NO_TOKEN_ALIGNMENT,
    prefix_cache: str | None = _PREFIX_CACHE,
    endpoint: str | None = _ENDPOINT,
    server_timeout: float | None = _SERVER_TIMEOUT,
    domain: str | None = typer.Option(None, help=DOMAIN_HELP),
) -> None:
    """Plan a task with a local model: decomposition, coalition, allocation; print the allocated plan."""
    options = ModelOptions.from_command(locals())
    if out is not None:
        check_output_folder(out, "--out")
    dom = load_domain(domain, catalogue=catalogue)
    cat = dom.catalogue
    refuse_household_options(dom, floor_plan, thor_build)
    goals, trans, max_trans = (), None, None
    if task is not None:
        if instruction or floor_plan or robots:
            raise UserError("give either --task (with --tasks) or an instruction with --floor-plan and --robots")
        chosen = find_task(load_tasks(tasks or dom.task_files(), catalogue=cat, domain=dom), task)
        instruction, scene, team_ids = chosen.instruction, chosen.floor_plan, list(chosen.robots)
        goals, trans, max_trans = chosen.goals, chosen.trans, chosen.max_trans
    else:
        if tasks is not None:
            raise UserError("--tasks needs --task ID")
        if not (instruction and (floor_plan or not dom.is_ai2thor) and robots):
            raise UserError('plan needs an instruction, --floor-plan and --robots (or --task ID), e.g. '
                            'smartllm-local plan "Put the apple in the fridge" --floor-plan 6 --robots 1,2'
                            if dom.is_ai2thor else "plan needs an instruction and --robots (or --task ID)")
        scene, team_ids = floor_plan_name(floor_plan) if dom.is_ai2thor else dom.site, parse_robot_ids(robots)
    team = cat.team(team_ids)
    if execute and dispatch is not None:
        raise UserError("give --execute (in AI2-THOR) or --dispatch (on the lab's robots), not both")
    functions = load_dispatch(dispatch, cat.skills) if dispatch is not None else None
    if functions is not None:  # the grammars offer every skill of the team: each needs its function
        missing = functions.unnamed(skill for robot in team for skill in robot.skills)
        if missing:
            raise UserError(f"the team's robots have skill(s) {', '.join(missing)}, which the dispatch file "
                            f"{dispatch} names no function for; add them under [skills]")
    planner = options.planners(cat, dom)[0]
    try:
        result = planner.plan(instruction, scene, team_ids)
    finally:
        planner.backend.close()
    for notice in result.notices:
        print(f"notice: {notice}", file=sys.stderr)
    scores = None
    if execute and result.plan is not None and not result.error:
        scores = execute_and_score(result, goals, cat, trans=trans, max_trans=max_trans,
                                   build=str(thor_build) if thor_build else None,
                                   site=dom.as_site)
    dispatched = None
    if functions is not None and result.plan is not None and not result.plan.is_refusal and not result.error:
        dispatched = dispatch_plan(result.plan, team, functions, skills=cat.skills)
    extra = {"model": planner.backend.model, "backend": planner.backend.name, "chat_template": planner.chat_status}
    if scores is not None:
        extra["metrics"] = scores.metrics()
    if dispatched is not None:
        extra["dispatch"] = {"attempted": dispatched.attempted, "succeeded": dispatched.succeeded,
                             **run_record(dispatched)}
    if out is not None:
        write_artifacts(result, out, extra)
    if as_json:
        typer.echo(json.dumps({"allocated": result.allocated, "refusal": result.refusal,
                               "error": result.error or None, **extra}))
    else:
        typer.echo(result.allocated or f"# no valid plan: {result.error}", nl=False)
        if scores is not None:
            fmt = lambda v: "n/a" if v is None else f"{v:.2f}"  # noqa: E731
            for description, ok in scores.conditions:
                typer.echo(f"  [{'x' if ok else ' '}] {description}")
            typer.echo(f"SR {fmt(scores.SR)}  TCR {fmt(scores.TCR)}  GCR {fmt(scores.GCR)}  "
                       f"RU {fmt(scores.RU)}  Exe {fmt(scores.Exe)}  transitions {scores.transitions}")
        if dispatched is not None:
            typer.echo("dispatched: " + "\n".join(dispatch_report(dispatched)))
    if result.error or (dispatched is not None and not dispatch_succeeded(dispatched)):
        raise typer.Exit(1)


def benchmark_run(
    ctx: typer.Context,
    out: Path = typer.Option(..., "--out", help=(
        "Folder for run.json, per-task artifacts, results.jsonl and summary.txt. A run stopped at any "
        "point (Ctrl-C, a crash, kill -9) and started again with the same arguments resumes here.")),
    restart: bool = typer.Option(False, "--restart", help="Discard the run --out holds and start over."),
    seeds: str | None = typer.Option(None, "--seeds", help=(
        "N (seeds --seed … --seed+N-1) or a list (0,3,7): every task once per seed (with --temperature "
        "above 0), each run in DIR/seed-<s>/; summary.txt gives each category's mean ± standard deviation "
        "over the seeds (the paper's Table II).")),
    method: str = typer.Option("smartllm", help=(
        f"{', '.join(METHODS)}: SMART-LLM's stages; the model's decomposition with robots at random (seeded) "
        "or by a rule (a capable robot, else the smallest capable team); the reference plans (no model).")),
    tasks: Path | None = _TASKS,
    category: str | None = typer.Option(None, help=f"Only this category: {', '.join(CATEGORIES)}."),
    task: list[str] | None = typer.Option(None, help="Only these task ids (repeatable)."),
    catalogue: Path | None = _CATALOGUE,
    thor_build: Path | None = _THOR_BUILD,
    model: str | None = _MODEL,
    backend: str = _BACKEND,
    n_ctx: int = _N_CTX,
    threads: int | None = _THREADS,
    n_gpu_layers: int = _GPU,
    seed: int = _SEED,
    temperature: float = _TEMPERATURE,
    no_comments: bool = _NO_COMMENTS,
    no_summary: bool = _NO_SUMMARY,
    no_coalition: bool = _NO_COALITION,
    no_grammar: bool = _NO_GRAMMAR,
    free_teams: bool = _FREE_TEAMS,
    chat_template: str = _CHAT_TEMPLATE,
    free_allocation: bool = _FREE_ALLOCATION,
    no_world_check: bool = _NO_WORLD_CHECK,
    no_loop_guard: bool = _NO_LOOP_GUARD,
    no_token_alignment: bool = _NO_TOKEN_ALIGNMENT,
    prefix_cache: str | None = _PREFIX_CACHE,
    endpoint: str | None = _ENDPOINT,
    workers: int = typer.Option(1, "--workers", help=(
        "--backend server: plan this many tasks at once, spread over the endpoints and their slots "
        "(llama-server -np N has N; vLLM batches them all). Through a server, plans can differ with it: see "
        "docs/servers-and-gpus.md.")),
    server_timeout: float | None = _SERVER_TIMEOUT,
    domain: str | None = typer.Option(None, help=DOMAIN_HELP),
) -> None:
    """Plan, execute and score every task of a task file; print a per-category table."""
    options = ModelOptions.from_command(locals())
    check_output_folder(out, "--out")
    dom = load_domain(domain, catalogue=catalogue)
    cat = dom.catalogue
    tasks_files = [tasks] if tasks else dom.task_files()
    check_category(category)
    chosen = load_tasks(tasks_files, catalogue=cat, domain=dom)
    if category is not None:
        chosen = [t for t in chosen if t.category == category]
    if task:
        chosen = [find_task(chosen, t) for t in task]
    if not chosen:
        raise UserError("no task matches the filters")
    if method not in METHODS:
        raise UserError(f"--method must be one of {', '.join(METHODS)}, not {method!r}")
    chosen_seeds = parse_seeds(seeds, seed)
    if len(chosen_seeds) > 1 and temperature == 0 and method != "decomp-random":
        raise UserError("--seeds needs --temperature above 0: greedy decoding writes the same plans for every seed")
    arguments = {k: v for k, v in ctx.params.items()
                 if k not in ("out", "restart", "seeds", "prefix_cache", "workers", "server_timeout")}
    model_path = None if method == "reference" else model_location(backend, model)
    runs = []
    for s in chosen_seeds:  # every run folder is checked before the model loads
        folder = out if seeds is None else out / f"seed-{s}"
        manifest = run_manifest({**arguments, "seed": s}, model_path, asdict(options.config_for(s)), tasks_files,
                                Path(cat.path), dom.prompts_dir())
        runs.append((s, RunStore(folder, manifest, restart=restart)))
    planners = [] if method == "reference" else options.planners(cat, dom)
    try:
        for s, store in runs:
            done = store.results()
            if done:
                print(f"resuming the run in {store.out}: {sum(t.id in done for t in chosen)} of {len(chosen)} "
                      "tasks done", file=sys.stderr)
            seeded = [Planner(p.backend, cat, options.config_for(s), p.examples, p.site) for p in planners] or [None]
            with RunProgress(f"seed {s}" if seeds is not None else "") as progress:
                run_benchmark(chosen, [make_method(method, cat, p, dom.plans_dir()) for p in seeded], cat,
                              out=store.out, store=store, build=str(thor_build) if thor_build else None,
                              progress=progress, domain=dom)
    except KeyboardInterrupt:
        scored = sum(t.id in store.results() for _, store in runs for t in chosen)
        print(f"interrupted: {scored} of {len(chosen) * len(runs)} tasks scored; the same command resumes the run",
              file=sys.stderr)
        raise typer.Exit(130) from None
    finally:
        for planner in planners:
            planner.backend.close()
    results = [store.results() for _, store in runs]
    per_run = [[lines[t.id] for t in chosen if t.id in lines] for lines in results]
    if seeds is None:
        typer.echo(summary_table(per_run[0]))
        typer.echo(f"results: {out / 'results.jsonl'}")
        return
    table = variability_table(per_run)
    write_atomic(out / "summary.txt", table + "\n")
    typer.echo(table)
    typer.echo(f"results: {', '.join(str(store.out / 'results.jsonl') for _, store in runs)}")


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
