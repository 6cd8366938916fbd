"""The heavy suite's whole-benchmark run (``python -m pytest -m heavy``): Gemma-3 over all 47 tasks through the
real CLI, llama.cpp and Controller. The default suite checks the same on a task of each category."""

from __future__ import annotations

import json

import pytest

from .conftest import benchmark_run
from .test_methods import check_every_task

pytestmark = pytest.mark.heavy


@pytest.fixture(scope="module")
def whole(tmp_path_factory):
    out = tmp_path_factory.mktemp("whole") / "gemma"
    return out, benchmark_run(out, "--model", "gemma3-270m", timeout=1800)


def test_every_benchmark_task_goes_through_all_stages_and_executes(whole, all_tasks):
    out, _ = whole
    check_every_task(out, all_tasks)


def test_progress_counts_every_stage_of_every_task(whole):
    out, proc = whole
    steps = [line for line in proc.stderr.splitlines() if line.startswith("[")]
    # a step per stage and per execution of each of the 47 tasks, then the end
    assert steps[0] == "[0/188] decomposition kitchen-01"
    assert any(line.startswith("[141/188] execution kitchen-01") for line in steps)
    lines = [json.loads(x) for x in (out / "results.jsonl").read_text().splitlines()]
    sr = sum(line.get("SR") or 0.0 for line in lines if line["feasible"]) / 40
    assert steps[-1].startswith(f"[188/188] done; SR so far {sr:.2f} over")
    assert steps[-1].endswith("over 40 feasible task(s)")
