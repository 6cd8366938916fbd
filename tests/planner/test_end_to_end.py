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
import re

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
    trace = json.loads((out / "trace.json").read_text())  # --execute --out keeps the execution (the run viewer's)
    actions, conditions = trace["actions"], trace["conditions"]
    assert trace["floor_plan"] == "FloorPlan1" and trace["transitions"] == summary["metrics"]["transitions"]
    assert (sum(a["success"] for a in actions) / len(actions) if actions else 0.0) == summary["metrics"]["Exe"]
    assert sum(c["met"] for c in conditions) / len(conditions) == summary["metrics"]["GCR"]


def test_the_plan_command_shows_a_line_per_stage_on_stderr_and_only_the_plan_on_stdout(kitchen01):
    """stderr is a pipe here: one plain line per stage as it ends, with its tokens, rate and time (besides the
    notices of dropped examples, printed after the plan); the first, whose examples the empty prefix store did not
    hold, says once that they were evaluated and are now kept."""
    lines = [line for line in kitchen01.stderr.splitlines() if not line.startswith("notice: ")]
    records = json.loads((kitchen01.out / "result.json").read_text())["stages"]
    assert [line.split(":")[0] for line in lines] == list(records) == ["decomposition", "coalition", "allocation"]
    assert records["decomposition"]["prompted"]
    for line, (stage, timings) in zip(lines, records.items()):
        if not timings["prompted"]:  # every line had one way to write it: the planner's, its prompt not evaluated
            said, seconds = re.fullmatch(r"(.*); (\d+\.\d) s in all", line).groups()
            assert timings["generated_tokens"] == 0 and said == (
                f"{stage}: nothing for the model to choose: {timings['forced_tokens']:,} tokens written by the "
                f"planner, the prompt ({timings['prompt_tokens']:,} tokens) not evaluated"), line
            assert abs(float(seconds) - timings["seconds"]) <= 0.05 + 1e-9, line  # the record keeps 3 decimals
            continue
        assert line.startswith(f"{stage}: prompt {timings['prompt_tokens']:,} tokens "
                               f"({timings['reused_tokens']:,} reused) in "), line
        written = timings["generated_tokens"] + timings["forced_tokens"]
        assert f"; {written:,} tokens written ({timings['generated_tokens']:,} by the model) in " in line
        assert re.search(r" in \d+\.\d s, \d+\.\d tokens/s; \d+\.\d s in all( \(|$)", line), line
    evaluated = records["decomposition"]["shared_tokens"] - records["decomposition"]["reused_tokens"]
    assert lines[0].endswith(f" s in all (its {evaluated:,} tokens of examples were evaluated, as they are the first "
                             f"time: they are now kept in the prefix store {kitchen01.states}, and later runs on "
                             "this model start from them)")
    assert sum("were evaluated" in line for line in lines) == 1
    allocated = (kitchen01.out / "allocated.py").read_text()
    assert kitchen01.stdout.startswith(allocated) and "tokens/s" not in kitchen01.stdout


def test_a_refusal_the_grammar_forces_is_told_from_one_the_model_chose(smollm2):
    """kitchen-inf-02's team cannot slice: once the model writes a SliceObject step, the coalition
    grammar admits only a refusal, and the result says the grammar refused, not the model."""
    from smartllm_local.planner.result import PlanResult, StageRecord
    catalogue = load_domain().catalogue
    task = next(t for t in load_tasks() if t.id == "kitchen-inf-02")
    decomposed = ("# SubTask 1: slice the potato (skills: GoToObject, PickupObject, SliceObject, PutObject)\n"
                  "# Alone.\n\ndef subtask1_slice():\n    GoToObject('Knife')\n    PickupObject('Knife')\n"
                  "    GoToObject('Potato')\n    SliceObject('Potato')\n    GoToObject('CounterTop')\n"
                  "    PutObject('Knife', 'CounterTop')\n\nsubtask1_slice()\n")
    plan = parse_plan(decomposed, form="decomposed")
    result = PlanResult(task.instruction, task.floor_plan, list(task.robots),
                        stages={"decomposition": StageRecord("decomposition", output=decomposed, plan=plan)})
    Planner(smollm2, catalogue).form_coalition(result)
    assert result.refusal is not None and result.refused_by == "grammar"
