"""The tables scripts/gpu_check.sh prints: per shape, the plan's stages and bench's prompt path and decoding; and
the benchmark runs with K tasks planned at once, in tasks per minute.

    python scripts/gpu_table.py WORK SHAPE...   (WORK holds SHAPE/<stage>/timings.json, bench-SHAPE.json, and
                                                 parallel-K/results.jsonl with parallel-K.wall for each K run)
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

HEADER = ("| shape | plan wall s | decomposition s (prompt s, prompt tokens) | coalition s (prompt s) "
          "| allocation s (prompt s) | prefill s / llama.cpp alone s (prefill_over_engine) | states kept, stored "
          "| decoding tok/s free, constrained |")


def stage_cells(run: Path) -> list[str]:
    cells = []
    for stage in ("decomposition", "coalition", "allocation"):
        timings = run / stage / "timings.json"
        if not timings.is_file():
            cells.append("- (refused before)")  # a random model may write the refusal line
            continue
        t = json.loads(timings.read_text())
        extra = f", {t['prompt_tokens']:,}" if stage == "decomposition" else ""
        cells.append(f"{t['seconds']:.1f} ({t['prompt_seconds']:.1f}{extra})")
    return cells


def bench_cells(bench: Path) -> list[str]:
    if not bench.is_file():
        return ["-", "-", "-"]
    model = next(iter(json.loads(bench.read_text())["models"].values()))
    prefill, decode = model["prefill"], model["decode"]
    ratio = prefill["prefill_over_engine"]
    return [f"{prefill['first']['seconds']:.2f} / {prefill['engine_s'] or 0:.2f} "
            f"({'-' if ratio is None else format(ratio, '.2f')})",
            f"{prefill['keeps_states']}, {prefill['stores_states']}",
            f"{decode['free']['tokens_per_s']:.0f}, {decode['constrained']['tokens_per_s']:.0f}"]


def parallel_rows(work: Path) -> list[str]:
    """A row per ``benchmark run --parallel K`` (the first shape's), in K's order: tasks scored, wall time, tasks
    per minute, and the tasks that ended in an error (a random model's plans fail often: they are still tasks)."""
    rows = []
    runs = sorted(work.glob("parallel-*.wall"), key=lambda path: int(path.stem.split("-")[1]))
    for wall_file in runs:
        k = wall_file.stem.split("-")[1]
        results = work / f"parallel-{k}" / "results.jsonl"  # absent where a run failed or was cut before a task
        lines = [json.loads(line) for line in results.read_text().splitlines()] if results.is_file() else []
        wall = int(wall_file.read_text().strip())
        rate = 60 * len(lines) / wall if wall else float("inf")
        errors = sum("error" in line for line in lines)
        rows.append(f"| {k} | {len(lines)} | {wall} | {rate:.1f} | {errors} |")
    return rows


def main(argv: list[str]) -> int:
    work, shapes = Path(argv[0]), argv[1:]
    print(HEADER)
    print("|---|---:|---:|---:|---:|---:|---|---:|")
    for shape in shapes:
        wall = (work / f"{shape}.wall").read_text().strip()
        cells = stage_cells(work / shape) + bench_cells(work / f"bench-{shape}.json")
        print(f"| {shape} | {wall} | " + " | ".join(cells) + " |")
    rows = parallel_rows(work)
    if rows:
        print(f"\nbenchmark run --parallel K on the {shapes[0]} shape (a new process each, the prefix store warm):\n")
        print("| K | tasks | wall s | tasks/min | tasks with an error |")
        print("|---:|---:|---:|---:|---:|")
        print("\n".join(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
