#!/usr/bin/env python
"""Per-stage cost of planning one task: prompt tokens, generated and forced tokens, seconds,
tokens/s, with the grammars and without them (free generation with stop strings); then the
model's raw prompt-evaluation and decoding speed on the decomposition prompt.

The run with grammars plans the task through all stages. The free run measures
every stage the grammar run reached, each on the same input: a free stage is fed
the grammar run's outputs of the earlier stages (free output is seldom a valid
plan, so a free pipeline would stop after the first stage), and its prompt is
checked to be the grammar run's. "valid" says whether the output is a valid
plan (decomposition, allocation) or list of coalition lines, or a refusal.

Each configuration gets a freshly loaded model and no prefix store on disk, so
both start with an empty cache (`smartllm-local bench` measures the reuse).
A stage's seconds include evaluating its prompt, less what the key/value
cache already held; forced tokens (text the grammar admits in one way only) are
written in one batch rather than decoded one by one.

Usage::

    python scripts/bench_planner.py [--task kitchen-09] [--backend llamacpp|transformers]
                                    [--model smollm2|gemma3-270m|PATH] [--threads N] [--n-gpu-layers N]
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Sequence

from smartllm_local.benchmark.tasks import Task, find_task, load_tasks
from smartllm_local.domain import load_domain
from smartllm_local.planner.backends import BACKENDS, Sampling, load_backend
from smartllm_local.planner.pipeline import Planner, PlannerConfig
from smartllm_local.planner.result import PlanResult, StageRecord


def raw_speed(args: argparse.Namespace, prompt: str, n: int = 64) -> tuple[float, float, int]:
    """(prompt tokens/s, decode tokens/s, decoded tokens): the prompt once, then n free tokens after it."""
    backend = load(args)
    try:
        tokens = backend.tokenize(prompt, bos=True)
        started = time.perf_counter()
        backend.generate(tokens, grammar=None, max_tokens=1, sampling=Sampling())
        prompt_rate = len(tokens) / (time.perf_counter() - started)
        started = time.perf_counter()
        out = backend.generate(tokens, grammar=None, max_tokens=n, sampling=Sampling())
        return prompt_rate, len(out.tokens) / (time.perf_counter() - started), len(out.tokens)
    finally:
        backend.close()


def load(args: argparse.Namespace):
    return load_backend(args.backend, args.model, threads=args.threads, n_gpu_layers=args.n_gpu_layers,
                        prefix_cache="off")


def free_stages(planner: Planner, task: Task, guided: PlanResult) -> list[StageRecord]:
    """Each stage the grammar run reached, run free on the grammar run's outputs of the earlier stages."""
    done = guided.stages
    scene = planner.scene(task.floor_plan)

    def fresh(*earlier: str) -> PlanResult:
        return PlanResult(instruction=task.instruction, floor_plan=scene.floor_plan, robots=list(task.robots),
                          stages={name: done[name] for name in earlier if name in done})

    steps = {"decomposition": (planner.decompose, ()), "coalition": (planner.form_coalition, ("decomposition",)),
             "allocation": (planner.allocate, ("decomposition", "coalition"))}
    decomposition = done.get("decomposition")
    records = []
    for name, (run, earlier) in steps.items():
        if name in done and (name == "decomposition" or (decomposition is not None and decomposition.plan is not None)):
            records.append(run(fresh(*earlier)))
    return records


def validity(record: StageRecord) -> str:
    if record.refusal is not None:
        return f"refusal: {record.refusal[:40]}"
    if not record.error:
        return "yes"
    problems = record.error.split(" is not a valid plan: ", 1)[-1].replace(f"<{record.stage} output>:", "line ")
    lines = problems.splitlines()
    more = f" (+{len(lines) - 1} more)" if len(lines) > 1 else ""
    return f"no: {lines[0][:60]}{more}"


def print_table(label: str, records: Sequence[StageRecord], guided: Sequence[StageRecord] = ()) -> None:
    print(f"\n{label}:")
    print(f"  {'stage':<14}{'prompt tok':>11}{'gen tok':>9}{'forced':>8}{'seconds':>9}{'tok/s':>8}  valid")
    prompts = {record.stage: record.prompt for record in guided}
    for record in records:
        same = "" if record.stage not in prompts or prompts[record.stage] == record.prompt else \
            "  (prompt differs from the grammar run's!)"
        print(f"  {record.stage:<14}{record.prompt_tokens:>11}{record.generated_tokens:>9}{record.forced_tokens:>8}"
              f"{record.seconds:>9.1f}{record.tokens_per_second:>8.1f}  {validity(record)}{same}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--task", default="kitchen-09")
    parser.add_argument("--backend", choices=BACKENDS, default="llamacpp")
    parser.add_argument("--model", default=None, help="an embedded model name or a path (default: smollm2)")
    parser.add_argument("--threads", type=int, default=None)
    parser.add_argument("--n-gpu-layers", type=int, default=0,
                        help="llama.cpp: layers on the GPU (-1 all); transformers: all-or-nothing")
    args = parser.parse_args()
    catalogue = load_domain().catalogue
    task = find_task(load_tasks(), args.task)
    print(f"task {task.id}: {task.instruction!r} on {task.floor_plan} with robots {list(task.robots)}")

    backend = load(args)
    try:
        guided = Planner(backend, catalogue, PlannerConfig(grammar=True)).plan(task.instruction, task.floor_plan,
                                                                               task.robots)
    finally:
        backend.close()
    print_table(f"with grammar ({args.backend}, {backend.model})", list(guided.stages.values()))

    backend = load(args)
    try:
        free = free_stages(Planner(backend, catalogue, PlannerConfig(grammar=False)), task, guided)
    finally:
        backend.close()
    print_table("without grammar (each stage fed the grammar run's outputs of the earlier stages)", free,
                list(guided.stages.values()))
    missing = [stage for stage in ("decomposition", "coalition", "allocation")
               if stage not in guided.stages]
    if missing:
        print(f"  not run: {', '.join(missing)} (the grammar run stopped before them: "
              f"{guided.refusal and 'refusal' or guided.error or 'no coalition stage'})")

    prompt_rate, decode_rate, decoded = raw_speed(args, guided.stage("decomposition").prompt)
    print(f"\nraw speed on the decomposition prompt: "
          f"prompt evaluation {prompt_rate:.0f} tok/s, decoding {decode_rate:.1f} tok/s ({decoded} tokens)")


if __name__ == "__main__":
    main()
