#!/usr/bin/env python
"""Per-stage cost of planning one task: prompt tokens, generated and forced tokens, seconds,
tokens/s, with the grammars and without them (free generation with stop strings); then the
model's raw prompt-evaluation and decoding speed on the decomposition prompt.

Each configuration gets a freshly loaded model, so both start with an empty
cache. A stage's seconds include evaluating its prompt, less what the key/value
cache already held; forced tokens (text the grammar admits in one way only) are
written in one batch rather than decoded one by one.

Usage::

    python scripts/bench_planner.py [--task kitchen-09] [--model smollm2|gemma3-270m|PATH] [--threads N]
"""

from __future__ import annotations

import argparse
import time

from smartllm_local.planner.backends import Sampling, load_backend
from smartllm_local.planner.pipeline import Planner, PlannerConfig
from smartllm_local.robots import load_catalogue
from smartllm_local.tasks import find_task, load_tasks


def raw_speed(model: str | None, threads: int | None, prompt: str, n: int = 64) -> tuple[float, float, int]:
    """(prompt tokens/s, decode tokens/s, decoded tokens): the prompt once, then n free tokens after it."""
    backend = load_backend("llamacpp", model, threads=threads)
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--task", default="kitchen-09")
    parser.add_argument("--model", default=None)
    parser.add_argument("--threads", type=int, default=None)
    args = parser.parse_args()
    catalogue = load_catalogue()
    task = find_task(load_tasks(), args.task)
    print(f"task {task.id}: {task.instruction!r} on {task.floor_plan} with robots {list(task.robots)}")
    for grammar in (True, False):
        backend = load_backend("llamacpp", args.model, threads=args.threads)
        try:
            planner = Planner(backend, catalogue, PlannerConfig(grammar=grammar))
            result = planner.plan(task.instruction, task.floor_plan, task.robots)
        finally:
            backend.close()
        label = "with grammar" if grammar else "without grammar"
        print(f"\n{label} ({backend.model}):")
        print(f"  {'stage':<14}{'prompt tok':>11}{'gen tok':>9}{'forced':>8}{'seconds':>9}{'tok/s':>8}  valid")
        for record in result.stages:
            valid = "refusal" if record.refusal else ("no: " + record.error[:40] if record.error else "yes")
            print(f"  {record.stage:<14}{record.prompt_tokens:>11}{record.generated_tokens:>9}{record.forced_tokens:>8}"
                  f"{record.seconds:>9.1f}{record.tokens_per_second:>8.1f}  {valid}")
        if grammar:
            first_prompt = result.stages[0].prompt
    prompt_rate, decode_rate, decoded = raw_speed(args.model, args.threads, first_prompt)
    print(f"\nraw speed on the decomposition prompt: "
          f"prompt evaluation {prompt_rate:.0f} tok/s, decoding {decode_rate:.1f} tok/s ({decoded} tokens)")


if __name__ == "__main__":
    main()
