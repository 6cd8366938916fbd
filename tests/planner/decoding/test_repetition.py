"""The loop guard: what counts as a loop, that no hand-written plan ever trips it, and the grammar's way out."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from smartllm_local.domain import load_domain
from smartllm_local.planner.constraints.coalition import CoalitionConstraint
from smartllm_local.planner.constraints.format import COMMENT_CHARS, MAX_SUBTASKS, text_run
from smartllm_local.planner.constraints.plan import PlanConstraint
from smartllm_local.planner.constraints.world_check import WorldCheck
from smartllm_local.planner.decoding.grammar import Grammar, alt, opt, seq
from smartllm_local.planner.decoding.matcher import Matcher
from smartllm_local.planner.decoding.protocol import Choose
from smartllm_local.planner.decoding.repetition import LoopGuard, current_line, draw
from smartllm_local.planner.decoding.sampling import Generated, Sampling
from smartllm_local.planner.result import StageRecord
from smartllm_local.planner.stages import Fitted, run_stage
from smartllm_local.worlds import scene_objects
from tests.planner.fakes import FakeBackend

DOMAINS = Path(__file__).resolve().parents[3] / "domains"
GUARD = LoopGuard()


@pytest.mark.parametrize("line", [
    "# SubTask 1: 1.1.1.1.1.",
    "# SubTask 2: Cut the glass of the glass of the glass of the",
    "; GoToObject, PickupObject, PickupObject, PickupObject, Pick",
    "# ---------",
    "    # so so so",
])
def test_a_third_copy_in_a_row_is_a_loop(line):
    assert GUARD.loops(line)


@pytest.mark.parametrize("line", [
    "# SubTask 1: 1.1.1.1.",  # short repeats must span 9 characters
    "# Sub-task three: fill the kettle...",
    "# SubTask 2: Cut the glass of the glass of the",  # two copies
    "# SubTask 1 (subtask1_toast): needs SwitchOn; robots[1] has SwitchOn; so robots[1]",
    "    PutObject(robot_list[0], 'Bread', 'CounterTop')",
    "",
])
def test_what_is_not_a_loop(line):
    assert not GUARD.loops(line)


@given(st.text(min_size=0, max_size=20), st.text(alphabet=sorted(COMMENT_CHARS), min_size=1, max_size=32),
       st.integers(min_value=1, max_value=12))
def test_a_unit_repeated_to_three_copies_and_nine_characters_is_found_after_any_text(before, unit, copies):
    """Whatever precedes it, a line ending in ``copies`` copies of ``unit`` loops once there are three of them
    spanning nine characters (and perhaps sooner, where the copies themselves repeat a shorter unit)."""
    if copies >= 3 and len(unit) * copies >= 9:
        assert GUARD.loops(before + unit * copies)


def _hand_written() -> list[Path]:
    files = [p for p in DOMAINS.glob("*/prompts/*/*") if p.suffix in (".py", ".txt")]
    return files + list(DOMAINS.glob("*/benchmark/reference_plans/*.py"))


def test_no_line_any_domain_writes_by_hand_is_ever_a_loop():
    """Every prefix of every line of the examples and the reference plans: the guard never cuts what a
    plan is meant to say, only what no example ever says."""
    files = _hand_written()
    assert len(files) > 60
    for path in files:
        for line in path.read_text(encoding="utf-8").splitlines():
            for end in range(len(line) + 1):
                assert not GUARD.loops(line[:end]), f"{path.name}: {line[:end]!r}"


CABINET = ["    # go to the cabinet", "    GoToObject('Cabinet')", "    OpenObject('Cabinet')",
           "    GoToObject('Cabinet')", "    CloseObject('Cabinet')"]


def test_a_line_that_begins_a_third_copy_of_a_block_of_lines_is_a_loop():
    """Qwen2.5-Coder-1.5B's cycle (go to, open, go to, close the cabinet): two copies stand, the first line
    of a third is a loop; three identical lines in a row are a block of one."""
    head = ["def subtask1_cabinet():"]
    assert not GUARD.cycles(head + CABINET * 2)
    assert GUARD.cycles(head + CABINET * 2 + CABINET[:1])
    assert GUARD.cycles(["x", "    # again", "    # again", "    # again"])
    assert not GUARD.cycles(["    # again", "    # again"])
    longest = [f"    Step{i}()" for i in range(GUARD.block)]
    assert GUARD.cycles(longest * 2 + longest[:1])
    assert not GUARD.cycles(["    Step()"] + longest * 2 + ["    Other()"])
    too_long = [f"    Step{i}()" for i in range(GUARD.block + 1)]
    assert not GUARD.cycles(too_long * 2 + too_long[:1])
    assert not LoopGuard(times=4).cycles(head + CABINET * 2 + CABINET[:1])


def test_the_same_steps_under_other_comments_are_the_same_loop():
    """The 1.5B's faucet cycle (bathroom-06, development half): go to, switch on, wait, switch off, each time under
    other comments. Two copies stand; the step that begins a third is a loop; a comment alone is not one."""
    def copy(where):
        return [f"    # go to the {where}", "    GoToObject('Faucet')", "    # run the water", "    SwitchOn('Faucet')",
                "    time.sleep(2)", "    SwitchOff('Faucet')"]
    lines = ["def subtask2_take_cloth():", *copy("bathtub"), *copy("basin")]
    assert not GUARD.cycles(lines)
    assert not GUARD.cycles([*lines, "    # go to the bathtub again"])
    assert GUARD.cycles([*lines, "    # go to the bathtub again", "    GoToObject('Faucet')"])


@given(st.lists(st.sampled_from(["a", "b", "c", ""]), max_size=8), st.lists(st.text(min_size=1), min_size=1,
                                                                           max_size=12))
def test_a_block_repeated_twice_and_begun_again_is_found_after_any_lines(before, block):
    assert GUARD.cycles(before + block * 2 + block[:1])


def test_no_plan_any_domain_writes_by_hand_ever_loops_its_lines():
    """Every line of every example and reference plan, with the lines before it: no hand-written plan repeats
    a block of lines twice and begins it again (nor even repeats one twice, today)."""
    for path in _hand_written():
        lines = path.read_text(encoding="utf-8").splitlines()
        for end in range(1, len(lines) + 1):
            assert not GUARD.cycles(lines[:end]), f"{path.name}: line {end}"


class _LoopingModel(FakeBackend):
    """Qwen2.5-Coder-1.5B's loop, as a model: it writes again the line four lines back wherever the grammar admits
    it, else the first line of its plan for the cabinet that the grammar admits; its tokens are characters, so
    its context can be read back."""

    PLAN = ["# SubTask 1: the cabinet (skills: GoToObject, OpenObject, CloseObject)\n", "# Alone.\n",
            "def subtask1_cabinet():\n", *(line + "\n" for line in CABINET[1:]), "\n", "subtask1_cabinet()\n"]

    def tokenize_continuation(self, text: str) -> list[int]:
        return [ord(c) for c in text]

    def generate(self, context, *, grammar, max_tokens, sampling, stop=(), rng=None, lines=1) -> Generated:
        written = "".join(chr(t) for t in context if t).split("\n")[:-1]
        again = [written[-4] + "\n"] if len(written) >= 4 else []
        forced = Matcher(grammar).forced()  # the carry the line begins with, and maybe more
        text = next(forced[:cut] + line for line in again + self.PLAN for cut in range(len(forced) + 1)
                    if grammar.matches(forced[:cut] + line))
        return Generated([ord(c) for c in text], text, "line")


@pytest.mark.parametrize("guarded", [True, False])
def test_a_stage_takes_back_the_line_that_begins_a_third_copy_and_writes_the_way_out(guarded):
    """A decomposition (world check) by a model that loops its lines: guarded, the line that would begin a third
    copy is taken out of the model's context (and of the raw output) and the function ends there, counted
    among the loops ended; unguarded, the loop runs on to the function's limit of steps."""
    scene = scene_objects(6)
    constraint = PlanConstraint(scene, load_domain().catalogue.skills,
                                world=WorldCheck(scene_objects(6), load_domain().catalogue.skills, MAX_SUBTASKS))
    record = StageRecord("decomposition")
    run_stage(record, _LoopingModel(), Fitted("prompt", [0] * 8), constraint, output_budget=1024,
              sampling=Sampling(loop_guard=LoopGuard() if guarded else None), rng=np.random.default_rng(0))
    lines = record.output.split("\n")
    loops = [end for end in range(1, len(lines) + 1) if GUARD.cycles(lines[:end])]
    assert "".join(chr(t) for t in record.context[8:]) == record.raw  # the context is what raw says
    if guarded:
        assert not loops and record.loops_ended >= 1, record.output
        assert not [end for end in range(1, 200) if GUARD.cycles(record.raw.split("\n")[:end])]
    else:
        assert loops and record.loops_ended == 0, record.output


def test_no_loop_guard_turns_it_off_and_labels_the_run():
    from smartllm_local.cli.options import ModelOptions
    from smartllm_local.report.runs import Run

    def options(off: bool) -> ModelOptions:
        return ModelOptions(n_ctx=4096, prefix_cache="off", no_loop_guard=off)

    assert options(False).config.sampling.loop_guard == LoopGuard()
    assert options(True).config.sampling.loop_guard is None
    run = Run(Path("."), [{"identity": {"arguments": {"no_loop_guard": True}}}])
    assert run.variant == "no loop guard"


def test_the_current_line_is_what_follows_the_last_newline():
    assert current_line("# a\n# b b") == "# b b"
    assert current_line("no newline") == "no newline"
    assert current_line("ends\n") == ""



def test_a_draw_avoids_what_it_is_told_to_while_anything_else_is_left():
    rng = np.random.default_rng(0)
    assert {draw(np.array([0.9, 0.05, 0.05, 0.0]), rng, lambda t: t == 0) for _ in range(200)} == {1, 2}
    assert draw(np.array([0.0, 1.0, 0.0]), rng, lambda t: True) == 1  # everything refused: the first draw
    assert {draw(np.array([0.5, 0.5]), rng) for _ in range(200)} == {0, 1}


# ------------------------------------------------------------------ the way out of free text

SUMMARY = Grammar({"root": seq("# SubTask 1: ", text_run(COMMENT_CHARS - set("()"), 60), " (skills: ",
                               alt("GoToObject", "PickupObject"), opt(", PutObject"), ")\n")})


def _after(grammar: Grammar, text: str) -> Matcher:
    matcher = Matcher(grammar)
    assert matcher.advance(text)
    return matcher


def test_the_way_out_leaves_the_free_text_and_stops_before_the_models_next_choice():
    """Out of a summary's text and up to its skills: never choosing a skill (GoToObject is shorter than
    PickupObject, but which to write stays the model's)."""
    assert _after(SUMMARY, "# SubTask 1: 1.1.1.1.").shortest_way() == " ("


def test_outside_free_text_there_is_no_way_to_take():
    assert _after(SUMMARY, "# Sub").shortest_way() == ""
    assert _after(SUMMARY, "# SubTask 1: a (skills: ").shortest_way() == ""


def test_a_comment_ends_with_its_line():
    comment = Grammar({"root": seq("    # ", text_run(COMMENT_CHARS, 48), "\n")})
    assert _after(comment, "    # it up it up it").shortest_way() == "\n"


def test_a_coalitions_reasoning_ends_where_its_team_begins():
    constraint = CoalitionConstraint(["subtask1_toast"], 2)  # the model writes needs and reasoning
    choose = constraint.next(2000)
    assert isinstance(choose, Choose)
    matcher = _after(choose.grammar, "# SubTask 1 (subtask1_toast): needs GoToObject; PickupObject, PickupObject,")
    way = matcher.shortest_way()
    assert way == ";"
    assert matcher.advance(way) and matcher.forced() == " so robots["


@given(st.text(alphabet=sorted(COMMENT_CHARS - set("()")), min_size=1, max_size=60).filter(lambda t: t[0] != " "))
def test_the_way_out_is_always_one_the_grammar_admits_and_leaves_nothing_more_to_force(text):
    """Whatever free text came before it (free text never opens with a space: after forced text the model's
    word keeps its own), the way out continues a text the grammar admits, and once it is
    taken there is no further way to force: the model chooses again."""
    matcher = _after(SUMMARY, "# SubTask 1: " + text)
    way = matcher.shortest_way()
    assert way and matcher.advance(way) and matcher.shortest_way() == ""
    assert matcher.advance(matcher.forced() + "GoToObject)\n") and matcher.accepting

# A context after which SmolLM2 goes on counting "1." to the end of any line it is given.
LOOPING = "Version: 1.1.1.1.1.1.1.1.1.1.1.1.1.1.1.1.1.1.1.1.1.1.1.1.1.1.1.1.1.1.\nVersion: "


def check_loop_guard(backend) -> None:
    """On a real model (called by each backend's tests): unguarded, the model fills a line's free text
    with its loop; guarded, the line leaves the free text at the third copy by the grammar's way out, and
    still matches the grammar."""
    grammar = Grammar({"root": seq(text_run(COMMENT_CHARS - {"("}, 60), " (done)\n")})
    context = backend.tokenize(LOOPING, bos=True)
    budget = grammar.max_length() + 1
    free = backend.generate(context, grammar=grammar, max_tokens=budget, sampling=Sampling(loop_guard=None))
    guarded = backend.generate(context, grammar=grammar, max_tokens=budget, sampling=Sampling())
    assert free.loops == 0 and GUARD.loops(free.text[: -len(" (done)\n")]), free.text
    assert guarded.loops == 1 and guarded.text.endswith(" (done)\n") and grammar.matches(guarded.text), guarded.text
    assert len(guarded.text) < len(free.text) and len(guarded.tokens) < len(free.tokens)
