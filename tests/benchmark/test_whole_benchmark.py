"""The heavy suite's whole-benchmark run (``python -m pytest -m heavy``): Gemma-3 over every task through the
real CLI, llama.cpp and Controller. The default suite checks the same on a task of each category."""

from __future__ import annotations

import json

import pytest

from tests.conftest import benchmark_run

from .test_methods import check_every_task

pytestmark = pytest.mark.heavy


@pytest.fixture(scope="module")
def whole(tmp_path_factory):
    out = tmp_path_factory.mktemp("whole") / "gemma"
    return out, benchmark_run(out, "--model", "gemma3-270m", timeout=1800)


def test_every_benchmark_task_goes_through_all_stages_and_executes(whole, all_tasks):
    out, _ = whole
    check_every_task(out, all_tasks)


def test_progress_counts_every_stage_of_every_task(whole, all_tasks, feasible):
    out, proc = whole
    steps = [line for line in proc.stderr.splitlines() if line.startswith("[")]
    # a step per stage and per execution of each task, then the end
    total = 4 * len(all_tasks)
    assert steps[0] == f"[0/{total}] decomposition kitchen-01"
    assert any(line.startswith(f"[{3 * len(all_tasks)}/{total}] execution kitchen-01") for line in steps)
    lines = [json.loads(x) for x in (out / "results.jsonl").read_text().splitlines()]
    sr = sum(line.get("SR") or 0.0 for line in lines if line["feasible"]) / len(feasible)
    assert steps[-1].startswith(f"[{total}/{total}] done; SR so far {sr:.2f} over")
    assert steps[-1].endswith(f"over {len(feasible)} feasible task(s)")
