"""The options several commands share, defined once: the model options (``plan``, ``benchmark run``,
``bench``) as :class:`ModelOptions` and the :func:`model_options` decorator that gives a command them, and
the domain, catalogue, build and task-file options."""

from __future__ import annotations

import functools
import inspect
import math
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import typer

from ..benchmark.methods import DEFAULT_TIME_LIMIT
from ..domain import Domain, load_domain
from ..errors import UserError
from ..planner.backends import (
    BACKENDS,
    Backend,
    LoopGuard,
    Sampling,
    check_server_options,
    load_backends,
    trained_context,
)
from ..planner.backends.prefix_cache import open_store
from ..planner.candidates import CANDIDATE_TEMPERATURE, Candidates
from ..planner.models import DEFAULT_MODEL, EMBEDDED, WITHOUT_SUMMARY, default_model, summary_for
from ..planner.parallel import PlannerSet
from ..planner.pipeline import Planner, PlannerConfig
from ..planner.prompting.chat import CHAT_TEMPLATE_MODES, mode_for
from ..planner.prompting.prompts import PromptOptions
from ..planner.verifier import SELECTORS
from ..worlds import world_of

DOMAIN_HELP = "The domain: household (the default), patrol, or a domain folder (see `smartllm-local domain`)."
CATALOGUE_HELP = "A JSON robot catalogue to use instead of an AI2-THOR domain's robots (default: the domain's own)."
THOR_BUILD_HELP = "A Unity AI2-THOR executable to run in (default: $SMARTLLM_THOR_BUILD, else the headless stand-in)."
MODEL_HELP = (f"A GGUF file (llama.cpp), a checkpoint folder or GGUF (transformers), or an embedded model: "
              f"{', '.join(EMBEDDED)} (default: {DEFAULT_MODEL}, or what SMARTLLM_MODEL names).")

#: The candidates a stage writes, and whether the goal stage runs first, unless the user says (chosen on the
#: development half: docs/measurements.md).
DEFAULT_CANDIDATES, DEFAULT_GOAL_CANDIDATES, DEFAULT_GOAL_CHECK = 1, 1, True
MAX_SEED = 2**32 - 1  # llama.cpp takes an unsigned 32-bit seed
DEFAULT_N_CTX = 8192  # or less, where the model was trained on less (the backends fit it within that)


class ModelOptions:
    """The model options of ``plan``, ``benchmark run`` and ``bench``, checked, turned into backends and planners."""

    def __init__(self, *, model: str | None = None, backend: str = "llamacpp", n_ctx: int | None = None,
                 threads: int | None = None, n_gpu_layers: int = 0, seed: int = 0, temperature: float = 0.0,
                 no_comments: bool = False, summary: bool | None = None, no_coalition: bool = False,
                 no_grammar: bool = False, free_teams: bool = False, chat_template: str = "auto",
                 free_allocation: bool = False, no_world_check: bool = False, prefix_cache: str | None = None,
                 endpoint: str | None = None, parallel: int = 1, server_timeout: float | None = None,
                 no_loop_guard: bool = False, no_token_alignment: bool = False,
                 candidates: int = DEFAULT_CANDIDATES, candidate_temperature: float = CANDIDATE_TEMPERATURE,
                 select: str = "verifier", goal_candidates: int = DEFAULT_GOAL_CANDIDATES,
                 goal_check: bool = DEFAULT_GOAL_CHECK, no_stop_at_goals: bool = False,
                 no_repair: bool = False, no_finish_goals: bool = False,
                 one_at_a_time: bool = False, keep_idle_steps: bool = False, finish_apart: bool = False,
                 keep_errands: bool = False, no_drafts: bool = False):
        _check_ranges(backend=backend, temperature=temperature, seed=seed, candidates=candidates,
                      goal_candidates=goal_candidates, candidate_temperature=candidate_temperature, select=select,
                      n_ctx=n_ctx, threads=threads, n_gpu_layers=n_gpu_layers)
        known = model if backend == "server" else model or default_model()
        if n_ctx is not None:
            _check_context(backend, model, n_ctx)
        chat_template = mode_for(known, chat_template)
        self.endpoints = [e.strip() for e in endpoint.split(",") if e.strip()] if endpoint else []
        check_server_options(backend, self.endpoints, parallel)
        if server_timeout is not None and not (math.isfinite(server_timeout) and server_timeout > 0):
            raise UserError(f"--server-timeout must be a number of seconds above 0, not {server_timeout}")
        self.parallel, self.server_timeout = parallel, server_timeout
        self.model, self.backend, self.threads = model, backend, threads
        self.n_ctx, self.n_ctx_given = (n_ctx if n_ctx is not None else DEFAULT_N_CTX), n_ctx is not None
        self.n_gpu_layers, self.drafts = n_gpu_layers, not no_drafts
        if prefix_cache is not None and not prefix_cache.strip():
            raise UserError("--prefix-cache needs a folder, or off (an empty one would fill the current folder)")
        self.prefix_cache = prefix_cache
        if backend == "llamacpp":  # a cache folder that can never be one fails before the model loads
            open_store(prefix_cache)
        self.config = PlannerConfig(
            sampling=Sampling(temperature=temperature, seed=seed, loop_guard=None if no_loop_guard else LoopGuard(),
                              aligned=not no_token_alignment),
            grammar=not no_grammar,
            free_teams=free_teams,
            prompts=PromptOptions(comments=not no_comments, summary=summary_for(known, summary),
                                  coalition=not no_coalition),
            chat_template=chat_template,
            restate=not free_allocation,
            world_check=not no_world_check,
            candidates=Candidates(candidates, candidate_temperature, select),
            goal_candidates=goal_candidates,
            goal_check=goal_check,
            stop_at_goals=not no_stop_at_goals,
            repair=not no_repair,
            finish_goals=not no_finish_goals,
            together=not one_at_a_time,
            drop_errands=not keep_errands,
            drop_idle=not keep_idle_steps,
            fold_finish=not finish_apart,
        )
        self.seed = seed

    def config_for(self, seed: int) -> PlannerConfig:
        """The planner's settings with another sampling seed."""
        return replace(self.config, sampling=replace(self.config.sampling, seed=seed))

    def load(self, prefix_cache: str | None = None) -> Backend:
        """One backend for this model (a server's first slot), its prefix states in ``prefix_cache``."""
        return self._backends(1, prefix_cache)[0]

    def _backends(self, workers: int, prefix_cache: str | None) -> list[Backend]:
        return load_backends(self.backend, self.model, workers=workers, endpoints=self.endpoints,
                             server_timeout=self.server_timeout, n_ctx=self.n_ctx, threads=self.threads,
                             n_gpu_layers=self.n_gpu_layers, seed=self.seed, prefix_cache=prefix_cache,
                             drafts=self.drafts)

    def as_arguments(self) -> list[str]:
        """The model's options as ``plan`` and ``benchmark run`` take them on the command line."""
        return [*(["--model", self.model] if self.model else []), "--backend", self.backend,
                *(["--endpoint", ",".join(self.endpoints)] if self.endpoints else []),
                *(["--server-timeout", str(self.server_timeout)] if self.server_timeout else []),
                *(["--n-ctx", str(self.n_ctx)] if self.n_ctx_given else []), "--n-gpu-layers", str(self.n_gpu_layers),
                "--chat-template", self.config.chat_template,
                *(["--threads", str(self.threads)] if self.threads else []),
                *([] if self.drafts else ["--no-drafts"])]

    def planners(self, catalogue, domain: Domain | None = None) -> list[Planner]:
        """One planner (a server backend's first slot), for ``domain``'s tasks."""
        world = world_of(domain or load_domain())
        return [Planner(backend, catalogue, self.config, world=world)
                for backend in self._backends(1, self.prefix_cache)]

    def open_planners(self, catalogue, domain: Domain | None = None, tasks: int | None = None) -> PlannerSet:
        """A planner per task planned at once (``--parallel``, at most ``tasks``): on lanes of one in-process
        llama.cpp model, or on a server's slots; one elsewhere. Close the set when done (it closes the backends)."""
        world = world_of(domain or load_domain())
        parallel = min(self.parallel, tasks or self.parallel)  # a lane is a task's key/value cache: none idle
        backends = self._backends(parallel if self.backend == "server" else 1, self.prefix_cache)
        return PlannerSet(backends, parallel if self.backend == "llamacpp" else 1,
                          lambda backend: Planner(backend, catalogue, self.config, world=world))


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
_N_CTX = typer.Option(None, "--n-ctx", show_default=False, help=(
    f"Context size in tokens, 512 or more (default: {DEFAULT_N_CTX}, or the model's trained context where that is "
    "shorter). More than the model was trained on is refused. Through --backend server the server's own context "
    "bounds it, and the trained context is checked only where --model names the served GGUF or tokenizer folder."))
_THREADS = typer.Option(None, help="CPU threads, 1 or more (default: all cores).")
_GPU = typer.Option(0, "--n-gpu-layers", help=(
    "Layers to offload to a GPU, -1 for all (needs a CUDA or Metal build of llama.cpp)."))
_SEED = typer.Option(0, help="Sampling seed.")
_TEMPERATURE = typer.Option(0.0, help="0 is greedy decoding.")
_NO_COMMENTS = typer.Option(False, "--no-comments", help="Ablation: examples without comments.")
_SUMMARY = typer.Option(None, "--summary/--no-summary", help=(
    "Decompositions that start by listing the sub-tasks (# SubTask k: ...), as the paper's prompts do, or not "
    f"(an ablation). Default: with it, but for the embedded models measured better without it: "
    f"{', '.join(sorted(WITHOUT_SUMMARY))}."), show_default=False)
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
_NO_DRAFTS = typer.Option(False, "--no-drafts", help=(
    "Evaluate each token as the model chooses it or the grammar forces it, rather than when its logits are next "
    "needed, in one batch with drafts from the context (faster on a CPU; a model whose logits move with the batch, "
    "as Qwen2.5-Coder's and SmolLM2's do, parts at near-ties; lanes evaluate so: see docs/planner.md, \"One "
    "decoding loop\"). llama.cpp only."))
_PREFIX_CACHE = typer.Option(None, "--prefix-cache", metavar="DIR|off", help=(
    "Where the examples' key/value states are kept between runs, so a later run on the same model starts "
    "from them (default: the user's cache, $XDG_CACHE_HOME/smartllm-local/prefix-states, at most 4 GiB); "
    "off keeps them for this run only. llama.cpp only."))
_PARALLEL = typer.Option(1, "--parallel", "--workers", metavar="K", help=(
    "Plan K tasks at once (default 1). --backend llamacpp: on one model in this process, their tokens "
    "evaluated in shared batches (worth it on a GPU, not on a few cores; greedy plans as with 1 where the model's "
    "logits do not change with the batch, as SmolLM2's; Qwen2.5-Coder's part at near-ties); --backend server: K "
    "requests at once, spread over the endpoints and their slots (llama-server -np K has K; vLLM batches them all). "
    "--workers is its former name. See docs/servers-and-gpus.md."))

_CANDIDATES = typer.Option(DEFAULT_CANDIDATES, "--candidates", envvar="SMARTLLM_CANDIDATES", help=(
    "Write the decomposition this many times (the first as --temperature says, greedy by default; the others "
    "sampled at --candidate-temperature) and keep the one --select chooses; 1 writes one, as before "
    "(see docs/planner.md, \"Candidates\")."))
_CANDIDATE_TEMPERATURE = typer.Option(CANDIDATE_TEMPERATURE, "--candidate-temperature", help=(
    "The sampling temperature of the second and later candidates."))
_SELECT = typer.Option("verifier", "--select", help=(
    "How a candidate is chosen: verifier (each dry-run in the world and checked against the goals the model "
    "stated) or likelihood (the model's mean log-probability alone)."))
_GOAL_CANDIDATES = typer.Option(DEFAULT_GOAL_CANDIDATES, "--goal-candidates", envvar="SMARTLLM_GOAL_CANDIDATES",
                                help=(
    "Write the goal statement this many times (the first as --temperature says, the others sampled at "
    "--candidate-temperature) and keep the one that says something of the most things the instruction names "
    "(a refusal where most refuse); 1 writes one (see docs/planner.md, \"The goal stage\")."))
_GOAL_CHECK = typer.Option(DEFAULT_GOAL_CHECK, "--goal-check/--no-goal-check", envvar="SMARTLLM_GOAL_CHECK", help=(
    "State the task's goals first (the goal stage) and refuse a task whose stated goals the team cannot meet "
    "(a state no robot's skill gives, a load too heavy for every lifter); the verifier checks candidates "
    "against them. With the grammar only."))
_NO_STOP_AT_GOALS = typer.Option(False, "--no-stop-at-goals", help=(
    "Let the decomposition begin another sub-task after the goals the goal stage stated all hold in the dry "
    "run, rather than end the plan there (for measuring what that changes; see docs/planner.md, \"Stopping at "
    "the stated goals\")."))
_NO_REPAIR = typer.Option(False, "--no-repair", help=(
    "Offer the decomposition only the calls that succeed where a sub-task stands, rather than also those that "
    "fail there and write them after the steps Fast Downward finds to enable them (a knife fetched before a "
    "slice; see docs/planner.md, \"Repair\")."))
_NO_FINISH_GOALS = typer.Option(False, "--no-finish-goals", help=(
    "End the decomposition where the model ends it, rather than have Fast Downward write a last sub-task that "
    "meets the stated goals the model's sub-tasks left unmet in the dry run, and steps that put a thing a "
    "sub-task's robot keeps in hand where they want it (see docs/planner.md, \"The planner's last sub-task\")."))

_ONE_AT_A_TIME = typer.Option(False, "--one-at-a-time", help=(
    "Let the allocation call a sub-task on its own or start a block of threads where the next sub-task could "
    "still join it, rather than have every sub-task that can join the block being written join it, and keep "
    "apart sub-tasks that can only run in turn rather than write them as one (see docs/planner.md, \"Threads "
    "together\")."))
_KEEP_IDLE_STEPS = typer.Option(False, "--keep-idle-steps", help=(
    "Keep the decomposition's pairs of steps that undo each other in a sub-task with nothing changed (a fridge "
    "opened and closed with nothing put in), rather than take them out before the teams are formed (see "
    "docs/planner.md, \"Idle steps\")."))
_KEEP_ERRANDS = typer.Option(False, "--keep-errands", help=(
    "Keep the decomposition's steps on a thing a sub-task acts on that nobody named and no stated goal is about, "
    "or that change nothing of how a named thing ends, and a step that alone makes sub-tasks run in turn, rather "
    "than take them out where the dry run shows them unneeded (see docs/planner.md, \"Errands\")."))
_FINISH_APART = typer.Option(False, "--finish-apart", help=(
    "Call the planner's last sub-task after the model's, rather than write its steps at the end of one of the "
    "model's sub-tasks where the dry run ends the same (one transition fewer; see docs/planner.md, \"The "
    "planner's last sub-task\")."))

#: Every model option: its parameter name, type and typer option, in the order --help lists them.
MODEL_PARAMETERS = [
    inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=option, annotation=kind)
    for name, kind, option in (
        ("model", str | None, _MODEL), ("backend", str, _BACKEND), ("n_ctx", int | None, _N_CTX),
        ("threads", int | None, _THREADS), ("n_gpu_layers", int, _GPU), ("seed", int, _SEED),
        ("temperature", float, _TEMPERATURE), ("no_comments", bool, _NO_COMMENTS),
        ("summary", bool | None, _SUMMARY), ("no_coalition", bool, _NO_COALITION),
        ("no_grammar", bool, _NO_GRAMMAR), ("free_teams", bool, _FREE_TEAMS),
        ("chat_template", str, _CHAT_TEMPLATE), ("free_allocation", bool, _FREE_ALLOCATION),
        ("no_world_check", bool, _NO_WORLD_CHECK), ("no_loop_guard", bool, _NO_LOOP_GUARD),
        ("no_token_alignment", bool, _NO_TOKEN_ALIGNMENT), ("no_drafts", bool, _NO_DRAFTS),
        ("prefix_cache", str | None, _PREFIX_CACHE),
        ("endpoint", str | None, _ENDPOINT), ("parallel", int, _PARALLEL),
        ("server_timeout", float | None, _SERVER_TIMEOUT), ("candidates", int, _CANDIDATES),
        ("candidate_temperature", float, _CANDIDATE_TEMPERATURE), ("select", str, _SELECT),
        ("goal_candidates", int, _GOAL_CANDIDATES),
        ("goal_check", bool, _GOAL_CHECK), ("no_stop_at_goals", bool, _NO_STOP_AT_GOALS),
        ("no_repair", bool, _NO_REPAIR), ("no_finish_goals", bool, _NO_FINISH_GOALS),
        ("one_at_a_time", bool, _ONE_AT_A_TIME), ("keep_idle_steps", bool, _KEEP_IDLE_STEPS),
        ("keep_errands", bool, _KEEP_ERRANDS), ("finish_apart", bool, _FINISH_APART),
    )
]


def model_options(*names: str, without: tuple[str, ...] = ()) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Give a command the model options ``names`` (all of them when none is named, less ``without``) after its
    own, passed to it as one ``model_settings`` dict of what the user gave (for :class:`ModelOptions`, which
    checks them).

    typer reads a command's options from its signature: the wrapper's signature is the command's own
    parameters (less ``model_settings``) and the chosen model parameters, so each option is declared once."""
    unknown = set(names + without) - {p.name for p in MODEL_PARAMETERS}
    if unknown:
        raise ValueError(f"no model option {', '.join(sorted(unknown))}")
    chosen = [p for p in MODEL_PARAMETERS if (not names or p.name in names) and p.name not in without]

    def decorate(command: Callable[..., Any]) -> Callable[..., Any]:
        own = [p for p in inspect.signature(command).parameters.values() if p.name != "model_settings"]

        @functools.wraps(command)
        def run(**arguments: Any) -> Any:
            settings = {p.name: arguments.pop(p.name) for p in chosen}
            return command(**arguments, model_settings=settings)

        run.__signature__ = inspect.Signature(own + chosen)  # type: ignore[attr-defined]
        run.__annotations__ = {**command.__annotations__, **{p.name: p.annotation for p in chosen}}
        run.__annotations__.pop("model_settings", None)
        return run

    return decorate


def given_path(value: str | Path) -> Path:
    """A file or folder to write, as an option gives it (or its default, a path): an empty one (an unset shell
    variable, say) is refused rather than taken for the current folder, where a run would write among the
    user's files."""
    if not str(value).strip():
        raise typer.BadParameter("an empty path: give a file or folder name")
    return Path(value)


CATALOGUE = typer.Option(None, help=CATALOGUE_HELP)
THOR_BUILD = typer.Option(None, help=THOR_BUILD_HELP)
TASKS = typer.Option(None, help="A task file (default: the project's benchmark).")
DOMAIN = typer.Option(None, help=DOMAIN_HELP)
PLANNER_TIME_LIMIT = typer.Option(DEFAULT_TIME_LIMIT, "--planner-time-limit", metavar="SECONDS", help=(
    "The goal-planner's search time per task; a task whose search runs out of it fails with an error."))
READ_STEPS = typer.Option(True, "--read-steps/--statement-only", help=(
    "The goal-planner: the model also decomposes the task, and where its steps put a thing the instruction "
    "names into a holder it names, the goal has it there, whatever the goal statement said "
    "(--statement-only: the statement alone, a decomposition fewer)."))


def _check_ranges(*, backend: str, temperature: float, seed: int, candidates: int, goal_candidates: int,
                  candidate_temperature: float, select: str, n_ctx: int | None, threads: int | None,
                  n_gpu_layers: int) -> None:
    """Refuse a model option's value out of its range (or not among its choices) before anything is read or
    loaded, each with what it must be."""
    if backend not in BACKENDS:
        raise UserError(f"--backend must be one of {', '.join(BACKENDS)}, not {backend!r}")
    if not math.isfinite(temperature) or temperature < 0:
        raise UserError(f"--temperature must be a number, 0 (greedy) or more, not {temperature}")
    if not 0 <= seed <= MAX_SEED:
        raise UserError(f"--seed must be between 0 and {MAX_SEED}, not {seed}")
    if candidates < 1:
        raise UserError(f"--candidates must be 1 or more, not {candidates}")
    if goal_candidates < 1:
        raise UserError(f"--goal-candidates must be 1 or more, not {goal_candidates}")
    if not math.isfinite(candidate_temperature) or candidate_temperature <= 0:
        raise UserError(f"--candidate-temperature must be a number above 0, not {candidate_temperature}")
    if select not in SELECTORS:
        raise UserError(f"--select must be one of {', '.join(SELECTORS)}, not {select!r}")
    if n_ctx is not None and n_ctx < 512:
        raise UserError(f"--n-ctx must be at least 512 tokens, not {n_ctx}")
    if threads is not None and threads < 1:
        raise UserError(f"--threads must be 1 or more, not {threads} (leave it out for all cores)")
    if n_gpu_layers < -1:
        raise UserError(f"--n-gpu-layers must be -1 (all), 0 (none, the default) or more, not {n_gpu_layers}")


def _check_context(backend: str, model: str | None, n_ctx: int) -> None:
    """Refuse a context longer than the model was trained on (where that can be read before it loads): past it a
    model's positions are ones it never learnt, and llama.cpp would only warn."""
    trained = trained_context(backend, model)
    if trained is not None and n_ctx > trained:
        name = model or ("the served model" if backend == "server" else default_model())
        raise UserError(f"--n-ctx {n_ctx} is more than the {trained:,} tokens {name} was trained on: give --n-ctx "
                        f"{trained} or less (left out, it is {min(DEFAULT_N_CTX, trained)})")


def refuse_household_options(dom: Domain, floor_plan: str | None, thor_build: Path | None) -> None:
    """AI2-THOR's floor plan and build options, given for a world that does not take them (a site domain's plans
    run on its one site), are refused rather than ignored."""
    world = world_of(dom)
    given = [name for name, value in (("--floor-plan", floor_plan), ("--thor-build", thor_build))
             if value and name not in world.options]
    if given:
        raise UserError(f"{' and '.join(given)} {'is' if len(given) == 1 else 'are'} for the household domain; "
                        f"the {dom.name} domain's plans run on {world.venue}")


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
