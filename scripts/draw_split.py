#!/usr/bin/env python
"""Draw a domain's development/test split and print it as ``benchmark/split.toml``.

Run once per domain: the household split was drawn with seed 43 and committed; tasks added since are
assigned by hand under ``[assigned]`` (see docs/benchmark.md, "The development/test split"). Drawing
again would move tasks between halves that prompts were already tuned on, so this refuses a domain
that has a split.

Usage::

    python scripts/draw_split.py household 43 > domains/household/benchmark/split.toml
"""

from __future__ import annotations

import json
import re
import sys

from smartllm_local.benchmark.split import draw
from smartllm_local.benchmark.tasks import load_tasks
from smartllm_local.domain import load_domain

HEADER = """\
# The {domain} benchmark's development/test split: see docs/benchmark.md, "The development/test split".
# Prompts, worked examples, candidate selectors and their settings are chosen on the dev half only; the test
# half is reported beside the whole. Infeasible tasks are in both halves and are not listed here.
#
# Every feasible task is in exactly one half: while one is in neither, `smartllm-local benchmark check`
# fails and `benchmark run --split` refuses to run. To add a task, add one line under [assigned],
#     my-new-task = "test"
# choosing the half that keeps its category's two halves within one task of each other (check says).

seed = {seed}
how = "{how}"

# What the seed drew from the {count} feasible tasks there were: never edited.
[drawn]
"""
HOW = ("each category's feasible task ids, sorted, shuffled in turn (elemental, simple, compound, complex) by "
       "Python's random.Random(seed); the first half of each (rounded down) to dev, the rest to test")
ASSIGNED = """
# Feasible tasks added after the draw, one line each: id = "dev" or "test".
[assigned]
"""


def main(args: list[str]) -> None:
    if len(args) != 2 or not args[1].isdigit():
        sys.exit(__doc__)
    domain = load_domain(args[0])
    if domain.split_file().is_file():
        sys.exit(f"{domain.split_file()} exists: add new tasks under its [assigned] instead of drawing again")
    tasks = load_tasks(domain=domain)
    halves = draw(tasks, int(args[1]))
    lines = []
    for half in ("dev", "test"):
        for category in dict.fromkeys(t.category for t in tasks if t.id in halves):
            lines.append(f"# {half}, {category}")
            lines += [f'{_key(t.id)} = "{half}"' for t in sorted(tasks, key=lambda t: t.id)
                      if t.category == category and halves.get(t.id) == half]
    sys.stdout.write(HEADER.format(domain=domain.name, seed=args[1], how=HOW, count=len(halves))
                     + "\n".join(lines) + "\n" + ASSIGNED)


def _key(task: str) -> str:
    """A task id as a TOML key: bare where TOML allows it, else quoted."""
    return task if re.fullmatch(r"[A-Za-z0-9_-]+", task) else json.dumps(task)


if __name__ == "__main__":
    main(sys.argv[1:])
