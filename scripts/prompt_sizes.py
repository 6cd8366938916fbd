#!/usr/bin/env python
"""Prompt sizes of the three stages over a benchmark run, measured with the run's own tokenizer.

Reads the ``results.jsonl`` that ``smartllm-local benchmark run --out DIR`` writes and prints, per
stage, the number of tasks that reached it and the smallest, median and largest prompt (tokens),
the mean number of tokens generated and the mean seconds, then how many tasks had to drop
allocation examples to fit the context.

Usage::

    python scripts/prompt_sizes.py runs/smollm2 [runs/gemma3 ...]
"""

from __future__ import annotations

import json
import statistics
import sys
from collections import Counter
from pathlib import Path

STAGES = ("decomposition", "coalition", "allocation")


def main(paths: list[str]) -> None:
    if not paths:
        sys.exit(__doc__)
    for path in paths:
        lines = (Path(path) / "results.jsonl").read_text().splitlines()
        results = [json.loads(line) for line in lines if line.strip()]
        print(f"{path}: {len(results)} tasks")
        print(f"  {'stage':<14}{'tasks':>6}{'min':>7}{'median':>8}{'max':>7}{'gen mean':>10}{'s mean':>8}")
        for stage in STAGES:
            rows = [r["tokens"][stage] for r in results if stage in r.get("tokens", {})]
            if not rows:
                continue
            prompts = [r["prompt"] for r in rows]
            print(f"  {stage:<14}{len(rows):>6}{min(prompts):>7}{statistics.median(prompts):>8.0f}{max(prompts):>7}"
                  f"{statistics.mean(r['generated'] for r in rows):>10.0f}"
                  f"{statistics.mean(r['seconds'] for r in rows):>8.1f}")
        dropped = Counter(_dropped_examples(r) for r in results if "allocation" in r.get("tokens", {}))
        print("  allocation examples dropped: "
              + ", ".join(f"{n} in {count} tasks" for n, count in sorted(dropped.items())))


def _dropped_examples(result: dict) -> int:
    for notice in result.get("notices", []):
        if notice.startswith("allocation: dropped example(s) "):
            names = notice.removeprefix("allocation: dropped example(s) ").split(" to fit")[0]
            return len(names.split(", "))
    return 0


if __name__ == "__main__":
    main(sys.argv[1:])
