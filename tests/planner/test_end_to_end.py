"""The planner end to end with the real embedded GGUF model: the plan command, refusals, the run records.

The outputs of a 135M-parameter model are poor plans; what is tested is that
every stage's output is a valid plan (or a refusal), that the plans execute
through the executor, and that the run records everything. A task of each
category through all three stages with a real model is in
tests/benchmark/test_methods.py (Gemma-3's run, shared with the report tests;
every task in the heavy suite).
"""

from __future__ import annotations

import json

from smartllm_local.benchmark.tasks import load_tasks
from smartllm_local.domain import load_domain
from smartllm_local.plan_language import parse_plan
from smartllm_local.planner.pipeline import Planner


def test_the_plan_command_writes_its_artifacts_and_executes(kitchen01):
    out = kitchen01.out
    assert "SR " in kitchen01.stdout and "Exe " in kitchen01.stdout
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
    from smartllm_local.planner.prompting.scene_context import scene_objects
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
