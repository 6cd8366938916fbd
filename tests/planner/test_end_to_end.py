"""The planner end to end with the real embedded GGUF model: every benchmark task through all three stages.

The outputs of a 135M-parameter model are poor plans; what is tested is that
every stage's output is a valid plan (or a refusal) for every task, that the
plans execute through the executor, and that the run records everything.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time

from smartllm_local.evaluation import run_benchmark
from smartllm_local.results import summary_table
from smartllm_local.plan_language import parse_plan
from smartllm_local.planner.pipeline import Planner
from smartllm_local.domain import load_domain
from smartllm_local.tasks import load_tasks


def test_every_benchmark_task_goes_through_all_stages_and_executes(smollm2, tmp_path):
    catalogue = load_domain().catalogue
    tasks = load_tasks()
    started = time.perf_counter()
    outcomes = run_benchmark(tasks, Planner(smollm2, catalogue), catalogue, out=tmp_path)
    elapsed = time.perf_counter() - started
    assert len(outcomes) == len(tasks) >= 42
    own = [o.seconds for o in outcomes]
    assert all(o.seconds >= sum(r.seconds for r in o.result.stages) > 0 for o in outcomes)
    assert sum(own) <= elapsed, "each task's seconds are its own, not its wait for the other tasks"
    for outcome in outcomes:
        result = outcome.result
        assert not outcome.error, (outcome.task.id, outcome.error)
        assert result is not None and result.plan is not None, outcome.task.id
        team = len(outcome.task.robots)
        parse_plan(result.allocated, form="allocated", team_size=team)
        if outcome.refused:
            continue
        assert [r.stage for r in result.stages] == ["decomposition", "coalition", "allocation"]
        parse_plan(result.stages[0].output, form="decomposed")
        assert all(line.startswith("# SubTask ") for line in result.stages[1].output.splitlines())
        if outcome.task.feasible:
            assert outcome.scores is not None, outcome.task.id
            assert 0.0 <= outcome.scores.Exe <= 1.0
    lines = (tmp_path / "results.jsonl").read_text().splitlines()
    assert [json.loads(line)["id"] for line in lines] == [t.id for t in tasks]
    assert (tmp_path / tasks[0].id / "allocated.py").is_file()
    table = summary_table([o.as_json() for o in outcomes])
    assert "all feasible" in table and "infeasible" in table


def test_the_plan_command_writes_its_artifacts_and_executes(tmp_path):
    out = tmp_path / "run"
    proc = subprocess.run(
        [sys.executable, "-m", "smartllm_local", "plan", "--task", "kitchen-01", "--out", str(out), "--execute"],
        capture_output=True, text=True, timeout=900,
    )
    assert proc.returncode == 0, proc.stderr
    assert "SR " in proc.stdout and "Exe " in proc.stdout
    for name in ("decomposed.py", "coalition.txt", "allocated.py", "result.json",
                 "decomposition/prompt.txt", "decomposition/grammar.gbnf", "decomposition/raw_output.txt",
                 "decomposition/timings.json", "allocation/timings.json"):
        assert (out / name).is_file(), name
    summary = json.loads((out / "result.json").read_text())
    assert set(summary["metrics"]) == {"SR", "TCR", "GCR", "RU", "Exe", "transitions"}
    assert summary["stages"]["decomposition"]["prompt_tokens"] > 1000


def test_a_refusal_the_grammar_forces_is_told_from_one_the_model_chose(smollm2):
    """kitchen-inf-02's team cannot slice: once the model writes a SliceObject step, the coalition
    grammar admits only a refusal, and the result says the grammar refused, not the model."""
    from smartllm_local.planner.pipeline import PlanResult
    from smartllm_local.planner.scene_context import scene_objects
    from smartllm_local.planner.stages import StageRecord

    catalogue = load_domain().catalogue
    task = next(t for t in load_tasks() if t.id == "kitchen-inf-02")
    decomposed = ("# SubTask 1: slice the potato (skills: GoToObject, PickupObject, SliceObject, PutObject)\n"
                  "# Alone.\n\ndef subtask1_slice():\n    GoToObject('Knife')\n    PickupObject('Knife')\n"
                  "    GoToObject('Potato')\n    SliceObject('Potato')\n    GoToObject('CounterTop')\n"
                  "    PutObject('Knife', 'CounterTop')\n\nsubtask1_slice()\n")
    plan = parse_plan(decomposed, form="decomposed")
    result = PlanResult(task.instruction, task.floor_plan, list(task.robots),
                        stages=[StageRecord("decomposition", output=decomposed, plan=plan)])
    Planner(smollm2, catalogue).form_coalition(result, plan, catalogue.team(task.robots),
                                               scene_objects(task.floor_plan))
    assert result.refusal is not None and result.refused_by == "grammar"
