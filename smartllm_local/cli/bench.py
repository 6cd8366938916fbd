"""``smartllm-local bench``: decoding speed, prefix reuse, the executor and the whole benchmark, in one run."""

from __future__ import annotations

from pathlib import Path

import typer

from ..bench import run_bench, summary
from ..domain import load_domain
from ..errors import UserError
from ..files import check_output_file, check_output_folder, json_text, write_atomic
from ..planner.backends import model_location
from ..planner.models import EMBEDDED
from ..tasks import load_tasks


def bench_command(
    models: str = typer.Option(",".join(EMBEDDED), "--models", help=(
        "Comma-separated GGUF files or embedded models, measured one after another (the first also runs "
        "the whole benchmark).")),
    sample: int = typer.Option(5, "--sample", help="Tasks (spread over the categories) for the decoding and "
                                                   "prefix-reuse figures."),
    whole_benchmark: bool = typer.Option(True, "--benchmark/--no-benchmark", help=(
        "Also time the whole benchmark with the first model (minutes).")),
    benchmark_out: Path | None = typer.Option(None, "--benchmark-out", help=(
        "Keep the whole benchmark's run folder here (a new folder, as `benchmark run --out` writes it), "
        "for `benchmark report`.")),
    threads: int | None = typer.Option(None, help="CPU threads (default: all cores)."),
    out: Path = typer.Option(Path("bench.json"), "--out", help="The JSON file to write."),
) -> None:
    """Measure, side by side: constrained and free decoding, prompt tokens and time to first token with
    and without the examples' kept states, executor speed, and the whole benchmark's time."""
    chosen = [m.strip() for m in models.split(",") if m.strip()]
    if not chosen:
        raise UserError("--models needs at least one model")
    if sample < 2:
        raise UserError("--sample must be at least 2: reuse shows from the second task on")
    check_output_file(out, "--out")
    if benchmark_out is not None and check_output_folder(benchmark_out, "--benchmark-out").exists():
        raise UserError(f"--benchmark-out {benchmark_out} exists: give a new folder")
    for model in chosen:  # every model is found before the first is measured
        model_location("llamacpp", model)
    household = load_domain()
    report = run_bench(chosen, household.catalogue, load_tasks(domain=household), sample=sample,
                       whole_benchmark=whole_benchmark, threads=threads, benchmark_out=benchmark_out)
    write_atomic(out, json_text(report))
    typer.echo(summary(report))
    typer.echo(f"written: {out}")
