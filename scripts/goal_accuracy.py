#!/usr/bin/env python
"""Measure the goal stage against a benchmark's goal conditions: precision and recall per category.

The stage gets each task's instruction and floor plan only (never its goals; see
smartllm_local/benchmark/goal_accuracy.py for how a stated condition is judged). Prints the table and,
with --out, writes one JSON line per task (what was stated, the task's conditions, the stage's timings).

Usage::

    python scripts/goal_accuracy.py --model qwen2.5-coder-0.5b [--split dev|test] [--goal-candidates N] [--out F]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from smartllm_local.benchmark.goal_accuracy import measure
from smartllm_local.benchmark.split import check_half, require_split, split_tasks
from smartllm_local.benchmark.tasks import load_tasks
from smartllm_local.cli.options import ModelOptions
from smartllm_local.domain import load_domain
from smartllm_local.files import write_atomic


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default=None, help="an embedded model or a GGUF path (default: the default model)")
    parser.add_argument("--domain", default="household")
    parser.add_argument("--split", default=None, help="dev or test: that half (and every infeasible task)")
    parser.add_argument("--out", type=Path, default=None, help="write one JSON line per task here")
    parser.add_argument("--n-ctx", type=int, default=8192)
    parser.add_argument("--goal-candidates", type=int, default=1, help="statements written per task, one kept")
    args = parser.parse_args(argv)
    domain = load_domain(args.domain)
    tasks = load_tasks(domain.task_files(), domain=domain)
    if args.split is not None:
        check_half(args.split)
        tasks = split_tasks(tasks, require_split(domain), args.split)
    options = ModelOptions(model=args.model, n_ctx=args.n_ctx, goal_candidates=args.goal_candidates)
    planner = options.planners(domain.catalogue, domain)[0]
    started = time.perf_counter()

    def state(instruction: str, floor_plan: str):
        stated = planner.goals(instruction, floor_plan)
        timings = stated.record.timings()
        print(f"{floor_plan}: {instruction} -> {stated.record.output.strip()!r}", file=sys.stderr, flush=True)
        return stated.statement, stated.refusal, {"seconds": timings["seconds"], "bending": timings["bending"],
                                                  "error": stated.error or None}

    try:
        report = measure(tasks, state)
    finally:
        planner.backend.close()
    seconds = time.perf_counter() - started
    print(f"goal stage, {planner.backend.model}, {args.domain} {args.split or 'all'} ({len(tasks)} tasks, "
          f"{seconds:.0f} s)")
    print(report.table())
    if args.out is not None:
        write_atomic(args.out, "".join(json.dumps(line) + "\n" for line in report.lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
