"""A stage tells its progress as it runs: started, prompt evaluated, its tokens so far, ended (the events the CLI
shows; tests/cli/test_plan_progress.py shows them, tests/planner/test_end_to_end.py has the real planner's)."""

from __future__ import annotations

import numpy as np

from smartllm_local.planner.decoding.grammar import Grammar, alt
from smartllm_local.planner.decoding.sampling import Sampling
from smartllm_local.planner.result import StageRecord
from smartllm_local.planner.stages import Fitted, run_stage

from .fakes import FakeBackend, Script


class Recorder:
    """Every event, in order."""

    def __init__(self):
        self.events: list[tuple] = []

    def stage_started(self, stage, prompt_tokens):
        self.events.append(("started", stage, prompt_tokens))

    def prompt_evaluated(self, stage, *, tokens, shared, reused, seconds):
        self.events.append(("evaluated", stage, tokens, shared, reused))

    def tokens_written(self, stage, generated, forced):
        self.events.append(("written", stage, generated, forced))

    def stage_ended(self, record):
        self.events.append(("ended", record))


class Reusing(FakeBackend):
    """Says it held the first ``held`` tokens of every prompt."""

    def __init__(self, held: int):
        super().__init__()
        self.held = held

    def prefill(self, context, prefixes) -> int:
        return self.held


def test_a_constrained_stage_tells_each_line_it_writes_then_its_end():
    recorder, record = Recorder(), StageRecord("decomposition")
    script = Script("# SubTask 1: wash\n", Grammar({"root": alt("def wash():\n", "def scrub():\n")}),
                    "    GoToObject('Sink')\n")
    run_stage(record, Reusing(3), Fitted("prompt", [1] * 10, prefixes=(6,)), script, output_budget=200,
              sampling=Sampling(), rng=np.random.default_rng(0), progress=recorder)
    events = recorder.events
    assert events[:2] == [("started", "decomposition", 10), ("evaluated", "decomposition", 10, 6, 3)]
    assert {e[:2] for e in events[2:-1]} == {("written", "decomposition")}
    written = [e[2:] for e in events[2:-1]]  # running totals (generated, forced), a line or a forced text at a time
    assert len(written) >= 2 and written == sorted(written)
    assert written[-1] == (record.generated_tokens, record.forced_tokens)
    assert record.generated_tokens > 0 and record.forced_tokens > 0
    assert events[-1] == ("ended", record) and record.output.startswith("# SubTask 1: wash\n")


def test_a_free_stage_tells_its_start_and_its_end():
    recorder, record = Recorder(), StageRecord("coalition")
    run_stage(record, FakeBackend(), Fitted("prompt", [1] * 4), None, output_budget=50, sampling=Sampling(),
              rng=np.random.default_rng(0), progress=recorder)
    assert [e[0] for e in recorder.events] == ["started", "evaluated", "ended"]
    assert recorder.events[-1][1].generated_tokens == 1


class Counting(FakeBackend):
    """Counts the prompts it is asked to evaluate."""

    def __init__(self):
        super().__init__()
        self.prefilled = 0

    def prefill(self, context, prefixes) -> int:
        self.prefilled += 1
        return 0


def test_a_stage_that_leaves_the_model_nothing_to_choose_never_evaluates_its_prompt():
    """Every line offered one way (an allocation whose robots the team leaves no choice of): the planner writes
    it all, the prompt is not evaluated (no prefill, no "evaluated" event), and the record says so; a stage with
    one choice evaluates it once, before the model's first line."""
    one_way = Script("def wash(robot_list):\n", Grammar({"root": alt("    GoToObject(robot_list[0], 'Sink')\n")}))
    recorder, record, backend = Recorder(), StageRecord("allocation"), Counting()
    run_stage(record, backend, Fitted("prompt", [1] * 10, prefixes=(6,)), one_way, output_budget=200,
              sampling=Sampling(), rng=np.random.default_rng(0), progress=recorder)
    assert record.output == "def wash(robot_list):\n    GoToObject(robot_list[0], 'Sink')\n"
    assert backend.prefilled == 0 and not record.prompted and record.generated_tokens == 0
    assert [e[0] for e in recorder.events] == ["started", "written", "ended"]
    choice = Script("def wash(robot_list):\n", Grammar({"root": alt("    GoToObject(robot_list[0], 'Sink')\n",
                                                                     "    GoToObject(robot_list, 'Sink')\n")}))
    recorder, record, backend = Recorder(), StageRecord("allocation"), Counting()
    run_stage(record, backend, Fitted("prompt", [1] * 10, prefixes=(6,)), choice, output_budget=200,
              sampling=Sampling(), rng=np.random.default_rng(0), progress=recorder)
    assert backend.prefilled == 1 and record.prompted and record.generated_tokens > 0
    assert [e[0] for e in recorder.events][:2] == ["started", "evaluated"]
