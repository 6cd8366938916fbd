"""The table scripts/gpu_check.sh prints: per shape, the plan's stages and bench's prompt path and decoding.

    python scripts/gpu_table.py WORK SHAPE...   (WORK holds SHAPE/<stage>/timings.json and bench-SHAPE.json)
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


def main(argv: list[str]) -> int:
    work, shapes = Path(argv[0]), argv[1:]
    print(HEADER)
    print("|---|---:|---:|---:|---:|---:|---|---:|")
    for shape in shapes:
        wall = (work / f"{shape}.wall").read_text().strip()
        cells = stage_cells(work / shape) + bench_cells(work / f"bench-{shape}.json")
        print(f"| {shape} | {wall} | " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
