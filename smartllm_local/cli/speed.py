"""``smartllm-local bench``: the prompt path, decoding, prefix reuse, the executor and the whole benchmark, in one
run, with each model run as ``plan`` runs it (its backend, GPU layers, context and chat template)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import typer

from ..benchmark.speed import run_bench, summary
from ..benchmark.tasks import load_tasks
from ..domain import load_domain
from ..errors import UserError
from ..files import check_output_file, check_output_folder, json_text, write_atomic
from ..planner.backends import model_location
from ..planner.models import EMBEDDED
from .options import ModelOptions, given_path, model_options


@model_options("backend", "endpoint", "server_timeout", "n_ctx", "n_gpu_layers", "chat_template", "threads")
def bench_command(
    models: str | None = typer.Option(None, "--models", help=(
        f"Comma-separated GGUF files or embedded models, measured one after another (the first also runs the "
        f"whole benchmark); default: {', '.join(EMBEDDED)}, or with --backend server the served model.")),
    sample: int = typer.Option(5, "--sample", help="Tasks (spread over the categories) for the decoding and "
                                                   "prefix-reuse figures."),
    whole_benchmark: bool = typer.Option(True, "--benchmark/--no-benchmark", help=(
        "Also time the whole benchmark with the first model (minutes).")),
    executor: bool = typer.Option(True, "--executor/--no-executor", help=(
        "Also time the executor on every reference plan.")),
    sharing: bool = typer.Option(True, "--sharing/--no-sharing", help=(
        "Also time `plan` of the first sample task with the first model alone, then two such processes at once "
        "(a user planning beside other work).")),
    benchmark_out: Path | None = typer.Option(None, "--benchmark-out", parser=given_path, metavar="DIR", help=(
        "Keep the whole benchmark's run folder here (a new folder, as `benchmark run --out` writes it), "
        "for `benchmark report`.")),
    out: Path = typer.Option(Path("bench.json"), "--out", parser=given_path, metavar="FILE",
                             help="The JSON file to write."),
    *,
    model_settings: dict[str, Any],
) -> None:
    """Measure, side by side: the prompt path against llama.cpp alone, constrained and free decoding, prompt
    tokens and time to first token with and without the examples' kept states, executor speed, and the whole
    benchmark's time."""
    backend = model_settings["backend"]
    if models is None:
        chosen: list[str | None] = [None] if backend == "server" else list(EMBEDDED)
    else:
        names = [m.strip() for m in models.split(",") if m.strip()]
        if not names:
            raise UserError("--models needs at least one model")
        twice = sorted({m for m in names if names.count(m) > 1})
        if twice:
            raise UserError(f"--models names {', '.join(twice)} more than once")
        chosen = list(names)
    if sample < 2:
        raise UserError("--sample must be at least 2: reuse shows from the second task on")
    check_output_file(out, "--out")
    if benchmark_out is not None and check_output_folder(benchmark_out, "--benchmark-out").exists():
        raise UserError(f"--benchmark-out {benchmark_out} exists: give a new folder")
    options = [ModelOptions(model=model, **model_settings) for model in chosen]
    for model in chosen:  # every model is found before the first is measured
        model_location(backend, model)
    household = load_domain()
    report = run_bench({model or "served": (o.load, o.config) for model, o in zip(chosen, options)},
                       household.catalogue, load_tasks(domain=household), sample=sample,
                       benchmark_options=options[0].as_arguments() if whole_benchmark else None,
                       benchmark_out=benchmark_out, executor=executor,
                       sharing_options=options[0].as_arguments() if sharing else None,
                       machine={"threads": model_settings["threads"] or os.cpu_count(), "backend": backend,
                                "n_gpu_layers": model_settings["n_gpu_layers"]})
    write_atomic(out, json_text(report))
    typer.echo(summary(report))
    typer.echo(f"written: {out}")
