#!/usr/bin/env python
"""Per-stage cost of planning one task: prompt tokens, generated tokens, seconds, tokens/s,
with the grammars and without them (free generation with stop strings).

Each configuration gets a freshly loaded model, so both start with an empty
cache. Seconds include evaluating the prompt; "decode tok/s" divides the
generated tokens by the time left after a prompt-only timing of the same prompt.

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


def prompt_seconds(model: str, threads: int | None, prompt: str) -> float:
    backend = load_backend("llamacpp", model, threads=threads)
    try:
        tokens = backend.tokenize(prompt, bos=True)
        started = time.perf_counter()
        backend.generate(tokens, grammar=None, max_tokens=1, sampling=Sampling())
        return time.perf_counter() - started
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
        print(f"  {'stage':<14}{'prompt tok':>11}{'gen tok':>9}{'seconds':>9}{'tok/s':>8}{'decode tok/s':>14}  valid")
        for record in result.stages:
            decode = record.seconds - prompt_seconds(args.model, args.threads, record.prompt)
            decode_rate = record.generated_tokens / decode if decode > 0 else float("nan")
            valid = "refusal" if record.refusal else ("no: " + record.error[:40] if record.error else "yes")
            print(f"  {record.stage:<14}{record.prompt_tokens:>11}{record.generated_tokens:>9}"
                  f"{record.seconds:>9.1f}{record.tokens_per_second:>8.1f}{decode_rate:>14.1f}  {valid}")


if __name__ == "__main__":
    main()
