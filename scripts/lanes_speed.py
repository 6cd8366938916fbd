#!/usr/bin/env python
"""Speed of lanes: a task's decomposition written by n lanes at once (lane 0 greedy, the others sampled, each its
own seed: a stage's candidates), against the backend writing it alone.

Each lane runs the planner's own decomposition stage (grammar, world check, loop guard) in a thread of its own;
their tokens are evaluated together (see smartllm_local/planner/backends/lanes.py). One JSON line per setting:
``lanes`` (n; 0 is the backend itself, one sequence, no lanes), ``wall_s`` (the n decompositions, prompt
included), ``prompt_s`` (until the last lane had its prompt), ``tokens`` (written by all lanes: the model's and
the grammar's), ``tokens_per_s`` (all lanes, after the prompt), ``per_lane_tokens_per_s``, ``batches``
(llama_decode calls) and ``prompt_tokens``.

Usage::

    python scripts/lanes_speed.py [--model qwen2.5-coder-0.5b|PATH] [--n-gpu-layers -1] [--lanes 1,4,8,16]
                                  [--task kitchen-01[,living-01...]] [--temperature 0.8] [--threads N]
                                  [--n-ctx 8192] [--unified]

Several tasks are spread over the lanes in turn (tasks planned at once rather than a task's candidates). No
prefix store on disk: each task is decomposed once first (not timed), which keeps its prompt's shared states in
memory, as a run keeps them, and every setting starts from those.
"""

from __future__ import annotations

import argparse
import json
import threading
import time

from smartllm_local.benchmark.tasks import find_task, load_tasks
from smartllm_local.domain import load_domain
from smartllm_local.planner.backends import Sampling, load_backend
from smartllm_local.planner.pipeline import Planner, PlannerConfig
from smartllm_local.planner.result import PlanResult


def decompose(backend, task, sampling: Sampling):
    planner = Planner(backend, load_domain().catalogue, PlannerConfig(sampling=sampling))
    scene = planner.scene(task.floor_plan)
    return planner.decompose(PlanResult(task.instruction, scene.floor_plan, list(task.robots)))


def setting(backend, n: int, tasks: list, temperature: float, unified: bool) -> dict:
    """Decompose with n lanes (0: the backend itself); the figures of one JSON line."""
    samplings = [Sampling(temperature=0.0 if i == 0 else temperature, seed=i) for i in range(max(n, 1))]
    records: list = [None] * max(n, 1)
    started = time.perf_counter()
    if n == 0:
        records[0] = decompose(backend, tasks[0], samplings[0])
        batches = None
    else:
        with backend.lanes(n, unified=unified) as views:
            def run(i: int) -> None:
                records[i] = decompose(views[i], tasks[i % len(tasks)], samplings[i])

            threads = [threading.Thread(target=run, args=(i,)) for i in range(n)]
            for thread in threads:
                thread.start()
            for thread in threads:
                thread.join()
            batches = views[0].batches
    wall = time.perf_counter() - started
    if any(r is None for r in records):
        raise SystemExit("a lane failed (see above)")
    prompt = max(r.prompt_seconds for r in records)
    tokens = sum(r.generated_tokens + r.forced_tokens for r in records)
    rate = tokens / (wall - prompt) if wall > prompt else 0.0
    return {"lanes": n, "task": ",".join(t.id for t in tasks), "wall_s": round(wall, 2), "prompt_s": round(prompt, 2),
            "prompt_tokens": records[0].prompt_tokens, "tokens": tokens, "tokens_per_s": round(rate, 2),
            "per_lane_tokens_per_s": round(rate / max(n, 1), 2), "batches": batches,
            "outputs_differ": len({r.output for r in records}), "errors": sum(bool(r.error) for r in records)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--model", default="qwen2.5-coder-0.5b")
    parser.add_argument("--n-gpu-layers", type=int, default=0)
    parser.add_argument("--threads", type=int, default=None)
    parser.add_argument("--n-ctx", type=int, default=8192)
    parser.add_argument("--lanes", default="1,4,8", help="comma-separated lane counts; 0 is the backend alone")
    parser.add_argument("--task", default="kitchen-01", help="a task id, or several separated by commas")
    parser.add_argument("--temperature", type=float, default=0.8, help="of every lane but the first")
    parser.add_argument("--unified", action="store_true", help="the lanes share one cache of n_ctx cells")
    args = parser.parse_args()
    tasks = [find_task(load_tasks(), name) for name in args.task.split(",")]
    backend = load_backend("llamacpp", args.model, n_ctx=args.n_ctx, threads=args.threads,
                           n_gpu_layers=args.n_gpu_layers, prefix_cache="off")
    try:
        for task in tasks:  # sets the device up and keeps the prompts' shared states, as in a run: not timed
            decompose(backend, task, Sampling())
        for n in [0, *(int(x) for x in args.lanes.split(","))]:
            row = setting(backend, n, tasks, args.temperature, args.unified)
            print(json.dumps({"model": args.model, "n_gpu_layers": args.n_gpu_layers, "unified": args.unified,
                              **row}), flush=True)
    finally:
        backend.close()


if __name__ == "__main__":
    main()
