"""``plan``'s progress display: a live line per stage on a terminal, a plain line per stage elsewhere, nothing
with --quiet; the examples' first evaluation explained once. The real command's lines on a pipe, and --quiet's
silence, are tested on real runs (tests/planner/test_end_to_end.py, tests/planner/backends/test_prefix_cache.py)."""

from __future__ import annotations

import io
import re

import pytest
from rich.console import Console

from smartllm_local.cli.progress import PlanProgress
from smartllm_local.planner.result import StageRecord

KEPT = "they are now kept in the prefix store /states, and later runs on this model start from them"
ESCAPE = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")


def _plan(progress: PlanProgress) -> None:
    """Two stages whose examples are evaluated (a fresh store), then one that reuses them all."""
    with progress:
        with progress.loading("the model smollm2"):
            pass
        for stage, reused in (("decomposition", 0), ("coalition", 0), ("allocation", 1500)):
            progress.stage_started(stage, 2000)
            progress.prompt_evaluated(stage, tokens=2000, shared=1500, reused=reused, seconds=12.5)
            progress.tokens_written(stage, 40, 10)
            progress.tokens_written(stage, 120, 37)
            progress.stage_ended(StageRecord(stage, prompt_tokens=2000, reused_tokens=reused, generated_tokens=120,
                                             forced_tokens=37, prompt_seconds=12.5, seconds=36.5))


SUMMARY = ("prompt 2,000 tokens ({reused} reused) in 12.5 s; 157 tokens written (120 by the model) in 24.0 s, "
           "6.5 tokens/s; 36.5 s in all")
NOTE = f"its 1,500 tokens of examples were evaluated, as they are the first time: {KEPT}"


def test_on_a_terminal_each_stage_is_left_with_its_summary_and_the_first_evaluation_is_explained_once():
    screen = io.StringIO()
    _plan(PlanProgress(Console(file=screen, force_terminal=True, width=250), kept=KEPT))
    shown = screen.getvalue()
    assert "\x1b[?25l" in shown  # a live display: the cursor hidden while it runs
    text = ESCAPE.sub("", shown)
    assert text.count(NOTE) == 1 and f"decomposition: the prompt took 12.5 s: {NOTE}" in text
    final = text.splitlines()[-3:]  # the display's last frame: a finished line per stage, the loading one gone
    assert [line.split()[:2] for line in final] == [["✓", "decomposition"], ["✓", "coalition"], ["✓", "allocation"]]
    for line, reused in zip(final, ("0", "0", "1,500")):
        assert line.rstrip().endswith(SUMMARY.format(reused=reused)), line
    assert "evaluating the prompt (2,000 tokens)" in text  # what each stage showed while its prompt ran


def test_on_a_narrow_terminal_the_detail_wraps_and_each_stage_and_its_time_stay_whole():
    screen = io.StringIO()
    _plan(PlanProgress(Console(file=screen, force_terminal=True, width=80), kept=KEPT))
    finished = [line for line in ESCAPE.sub("", screen.getvalue()).splitlines() if line.startswith("✓")][-3:]
    assert [re.match(r"✓ (\w+) +\d+:\d\d:\d\d prompt 2,000 tokens", line).group(1) for line in finished] == [
        "decomposition", "coalition", "allocation"]


def test_elsewhere_each_stage_is_one_plain_line_and_the_explanation_rides_on_the_first():
    log = io.StringIO()
    _plan(PlanProgress(Console(file=log, force_terminal=False), kept=KEPT))
    assert log.getvalue().splitlines() == [
        f"decomposition: {SUMMARY.format(reused=0)} ({NOTE})",
        f"coalition: {SUMMARY.format(reused=0)}",
        f"allocation: {SUMMARY.format(reused='1,500')}",
    ]


@pytest.mark.parametrize("terminal", [True, False])
def test_quiet_shows_nothing(terminal):
    out = io.StringIO()
    _plan(PlanProgress(Console(file=out, force_terminal=terminal), kept=KEPT, quiet=True))
    assert out.getvalue() == ""


def test_a_backend_that_does_not_say_what_it_reused_gets_no_explanation():
    log = io.StringIO()
    _plan(PlanProgress(Console(file=log, force_terminal=False), kept=None))
    assert "evaluated" not in log.getvalue() and len(log.getvalue().splitlines()) == 3


@pytest.mark.parametrize("terminal", [True, False])
def test_a_stage_no_model_writes_shows_what_it_found_or_its_error(terminal):
    """The goal-planner's search: no prompt to evaluate, no tokens; its line says what it found, or why not."""
    out = io.StringIO()
    found = StageRecord("allocation", output="# goal-planner: Fast Downward's shortest plan, 6 steps\n#\nimport x\n",
                        seconds=0.42)
    failed = StageRecord("allocation", error="the goal holds already: there is nothing to plan", seconds=0.7)
    with PlanProgress(Console(file=out, force_terminal=terminal, width=250)) as progress:
        for record in (found, failed):
            progress.stage_started("allocation", 0)
            progress.stage_ended(record)
    text = ESCAPE.sub("", out.getvalue())
    assert "evaluating the prompt" not in text and "tokens" not in text
    assert "goal-planner: Fast Downward's shortest plan, 6 steps; 0.4 s in all" in text
    assert "the goal holds already: there is nothing to plan; 0.7 s in all" in text
    if not terminal:
        assert text.splitlines() == ["allocation: goal-planner: Fast Downward's shortest plan, 6 steps; 0.4 s in all",
                                     "allocation: the goal holds already: there is nothing to plan; 0.7 s in all"]
    else:
        assert "planning without the model" in text


def test_a_stage_the_planner_wrote_alone_says_its_prompt_was_not_evaluated():
    """An allocation whose every line was one way to write: no model asked, so no prompt evaluated or tokens/s."""
    out = io.StringIO()
    record = StageRecord("allocation", prompt_tokens=3800, forced_tokens=201, seconds=0.3)
    with PlanProgress(Console(file=out, force_terminal=False)) as progress:
        progress.stage_started("allocation", 3800)
        progress.tokens_written("allocation", 0, 201)
        progress.stage_ended(record)
    assert out.getvalue().splitlines() == [
        "allocation: nothing for the model to choose: 201 tokens written by the planner, the prompt (3,800 tokens) "
        "not evaluated; 0.3 s in all"]
