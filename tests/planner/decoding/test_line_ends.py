"""Line ends as models write them: opened line grammars, and the driver reading what a token wrote past a
line's newline (a blank line ending a function, an indentation, a ``#``), forced text carried into the next
line, and the model ending the sequence. A scripted writer cuts a plan where a model's tokens would."""

from __future__ import annotations

import pytest

from smartllm_local.plan_language import parse_plan
from smartllm_local.planner.constraints.plan import PlanConstraint
from smartllm_local.planner.decoding.grammar import Grammar, alt, seq
from smartllm_local.planner.decoding.line_ends import BLANKS, COMMENT_NEXT, INDENTED_NEXT, open_ends
from smartllm_local.planner.decoding.matcher import Matcher
from smartllm_local.planner.decoding.protocol import Choose
from smartllm_local.planner.decoding.writer import Line, Report, TokenWriter, Written, run_tokens
from smartllm_local.skills import DEFAULT_SKILL_SET
from smartllm_local.worlds import scene_objects


def test_an_opened_line_admits_spaces_before_its_newline_and_what_may_follow_after_it():
    step = {"action": seq("    GoToObject('Apple')", "\n"), "end": "\n"}
    grammar = open_ends(step, {}, {"action": INDENTED_NEXT})
    for text in ("    GoToObject('Apple')\n", "    GoToObject('Apple')   \n", "    GoToObject('Apple')\n\n\n",
                 "    GoToObject('Apple')\n    ", "\n", "    \n", "\n\n"):
        assert grammar.matches(text), text
    for text in ("    GoToObject('Apple')\n     ", "    GoToObject('Apple')\n    G", "    GoToObject('Apple') x\n",
                 "\n    ", "    GoToObject('Apple')\n\n    "):
        assert not grammar.matches(text), text
    summary = open_ends({"summary": seq("# SubTask 1: x", "\n")}, {}, {"summary": COMMENT_NEXT})
    assert summary.matches("# SubTask 1: x\n#") and not summary.matches("# SubTask 1: x\n##")
    assert open_ends({"line": seq("x", "\n")}, {}, {}).matches("x\n\n") and Grammar({"root": BLANKS}).matches("")


class Tokens(TokenWriter):
    """Writes ``raw`` as a model would, its tokens ending at ``cuts`` (each answer runs to the first cut at or
    past the line's newline); ``end_at``: where it ends the sequence instead."""

    def __init__(self, raw: str, cuts: list[int], end_at: int | None = None):
        self.raw, self.cuts, self.end_at, self.at = raw, sorted(cuts), end_at, 0
        self.lines: list[Line] = []

    def write(self, line: Line, remaining: int) -> Written:
        self.lines.append(line)
        assert self.raw.startswith(line.carry, self.at), (self.raw[self.at:], line.carry)
        newline = self.at - 1
        for _ in range(line.lines):
            newline = self.raw.index("\n", newline + 1)
        if self.end_at is not None and self.at <= self.end_at <= newline:
            text, self.at = self.raw[self.at:self.end_at], len(self.raw)
            return Written(text, len(text) + 1, ended=True)
        end = next(c for c in self.cuts if c > newline)
        text, self.at = self.raw[self.at:end], end
        assert Matcher(line.grammar).advance(text), (line.grammar.to_gbnf(), text)
        return Written(text, len(text))

    def force(self, text: str) -> int:
        return len(text)


SUMMARY = "# SubTask 1: wash the apple (skills: GoToObject, PickupObject, PutObject)\n"
# A model's text with its line ends as code tokenizers write them: "\n#" after the summary, a blank line in
# the order line's last token ("\n\n", the blank the plan forces), trailing spaces, the indentation in a
# header's and a step's last token, the end of the function in its last step's ("')\n\n\n", one blank too many).
RAW = (SUMMARY + "# Alone. \n\n"
       "def subtask1_wash_apple():\n   "
       " GoToObject('Apple')\n    PickupObject('Apple')  \n\n\n"
       "subtask1_wash_apple()\n")
PLAN = (SUMMARY + "# Alone.\n\n"
        "def subtask1_wash_apple():\n    GoToObject('Apple')\n    PickupObject('Apple')\n\n"
        "subtask1_wash_apple()\n")


def _cuts(raw: str, *after: str) -> list[int]:
    """Token ends: after each newline run (with the spaces or ``#`` that follow where ``after`` says so)."""
    cuts = {len(raw)}
    for k, c in enumerate(raw):
        if c == "\n" and raw[k + 1:k + 2] != "\n":
            cuts.add(k + 1)
    for text in after:
        at = raw.index(text)
        cuts.discard(at + text.index("\n") + 1)
        cuts.add(at + len(text))
    return sorted(cuts)


def _constraint() -> PlanConstraint:
    return PlanConstraint(scene_objects(6), DEFAULT_SKILL_SET)


def test_tokens_past_a_line_end_go_on_into_the_next_line_and_the_plan_is_read_normalized():
    writer = Tokens(RAW, _cuts(RAW, ")\n#", "():\n   ", "Alone. \n\n", "')  \n\n\n"))
    report = Report()
    text = run_tokens(_constraint(), writer, 2000, report)
    assert text == PLAN
    parse_plan(text, form="decomposed")
    assert report.spilled == 4 and report.ignored_blank_lines == 1 and report.completed_lines == 0
    # the "#" and the indentation written ahead begin the next line; the blank the plan forces after the order
    # line, written in its last token, is not written again
    assert [line.ahead for line in writer.lines if line.ahead] == ["#", "   "]
    assert all(line.carry == "" for line in writer.lines)


def test_forced_text_goes_into_the_next_line_the_model_writes():
    raw = PLAN
    writer = Tokens(raw, [k + 1 for k, c in enumerate(raw) if c == "\n"])
    assert run_tokens(_constraint(), writer, 2000) == PLAN
    carried = [line.carry for line in writer.lines if line.carry]
    assert carried == ["\n"]  # the blank after the order line, written with the header that follows it
    assert writer.lines[2].grammar.matches("\ndef subtask1_wash_apple():\n")


@pytest.mark.parametrize("at", [PLAN.index(" the apple ("), PLAN.index("ToObject('Apple')"),
                                PLAN.rindex("subtask1_wash_apple()")])
def test_a_model_that_ends_the_sequence_gets_its_plan_completed_by_the_shortest_way(at):
    writer = Tokens(PLAN, _cuts(PLAN), end_at=at)
    report = Report()
    text = run_tokens(_constraint(), writer, 2000, report)
    assert text.startswith(PLAN[:at]) and report.completed_lines >= 1
    parse_plan(text, form="decomposed")
    assert report.notes and "ended the sequence" in report.notes[0]


def test_a_blank_line_where_nothing_may_end_is_read_as_none():
    """After a comment a step must follow: a blank line written there (a model's "\\n\\n") ends nothing."""
    raw = (SUMMARY + "# Alone.\n\ndef subtask1_wash_apple():\n    # first the apple\n\n"
           "    GoToObject('Apple')\n    PickupObject('Apple')\n\nsubtask1_wash_apple()\n")
    writer = Tokens(raw, _cuts(raw, "apple\n\n"))
    report = Report()
    text = run_tokens(_constraint(), writer, 2000, report)
    assert text == raw.replace("apple\n\n", "apple\n") and report.ignored_blank_lines == 1


def test_a_spill_is_checked_against_what_the_plan_offers_next():
    """A writer that runs past a line's end into text the next line cannot begin with is a planner bug, told
    as such (the grammar's follows never admit one)."""
    from smartllm_local.planner.decoding.protocol import Constraint
    from smartllm_local.planner.decoding.writer import GuaranteeError

    class Two(Constraint):
        def next(self, remaining):
            if self.text.count("\n") >= 2:
                return None
            g = Grammar({"root": seq(alt("a", "c") if not self.text else alt("b", "c"), "\n")})
            self._offered = Choose(g, {"line": g}, {"line": COMMENT_NEXT})
            return self._offered

        def _advance(self, kind, piece):
            pass

        def minimum_budget(self):
            return 4

    with pytest.raises(GuaranteeError, match="'#' was written where the plan goes on"):
        run_tokens(Two(), Tokens("a\n#b\n", [3, 5]), 100)
