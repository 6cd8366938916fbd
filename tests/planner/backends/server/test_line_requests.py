"""How a line is asked of a server, around a scripted stand-in for one (one token per character). That a
real server then writes the in-process backend's plans is tested in test_server_backend.py."""

from __future__ import annotations

import pytest

from smartllm_local.planner.backends.server.line_requests import LineRequests, WrongLine
from smartllm_local.planner.constraints.format import COMMENT_CHARS, text_run
from smartllm_local.planner.decoding.grammar import Grammar, Ref, alt, seq
from smartllm_local.planner.decoding.matcher import Matcher
from smartllm_local.planner.decoding.repetition import LoopGuard
from smartllm_local.planner.decoding.sampling import Sampling

PUT = Grammar({"obj": alt("'Apple'", "'Fridge'"), "root": seq("    PutObject(", Ref("obj"), ", 'Bowl')\n")})
CONTEXT = [1, 2, 3]


def spell(text: str) -> list[int]:
    return [1000 + ord(c) for c in text]  # forced text: tokens of its own, told apart from the server's


def text_of(token: int) -> str:
    return chr(token % 1000)


class Scripted:
    """Writes ``line`` on from wherever the text stands (or ``wrong``), and records each request."""

    def __init__(self, line: str, wrong: str | None = None):
        self.line, self.wrong, self.asked = line, wrong, []

    def __call__(self, context, grammar, limit, banned):
        written = "".join(text_of(t) for t in context[len(CONTEXT):])
        self.asked.append((written, grammar.to_gbnf(), limit, list(banned)))
        rest = self.wrong if self.wrong is not None else self.line[len(written):]
        return [ord(c) for c in rest if ord(c) not in banned][:limit], None


def test_the_planner_writes_what_the_grammar_forces_and_asks_only_where_the_model_chooses():
    server = Scripted("    PutObject('Fridge', 'Bowl')\n")
    line = LineRequests(CONTEXT, PUT, Sampling(), server, spell, text_of).write(100)
    assert line.text == server.line and line.stop == "line"
    # Forced text is written up to its last token, which the model writes (token healing): a request before
    # the quote, whose answer is kept up to the F (after it the grammar forces text again), and one for the
    # newline, after the planner wrote the rest.
    assert [written for written, *_ in server.asked] == ["    PutObject(", "    PutObject('Fridge', 'Bowl')"]
    assert server.asked[0][1] == PUT.after("    PutObject(").to_gbnf()
    assert line.tokens == spell("    PutObject(") + [ord("'"), ord("F")] + spell("ridge', 'Bowl')") + [ord("\n")]
    assert line.forced == len("    PutObject(") + len("ridge', 'Bowl')")


def test_a_server_that_writes_outside_the_grammar_is_caught():
    with pytest.raises(WrongLine, match=r"PutObject\('P"):
        LineRequests(CONTEXT, PUT, Sampling(), Scripted("", wrong="'Pear'"), spell, text_of).write(100)


NOTE = Grammar({"root": seq("# ", text_run(COMMENT_CHARS, 48), "\n")})


def test_a_loop_in_free_text_ends_by_the_grammars_way_out_and_the_rest_of_the_answer_is_dropped():
    server = Scripted("# 1.1.1.1.1.1.1.1.1.1.1.1.1.1.1.1.1.1.1.1\n")
    line = LineRequests(CONTEXT, NOTE, Sampling(loop_guard=LoopGuard()), server, spell, text_of).write(100)
    assert line.loops == 1 and line.text.endswith("\n") and NOTE.matches(line.text)
    assert line.tokens[-1] == spell("\n")[0]  # the way out is the planner's, not the server's
    unguarded = LineRequests(CONTEXT, NOTE, Sampling(loop_guard=None), server, spell, text_of).write(100)
    assert unguarded.text == server.line and unguarded.loops == 0


class NoGoA:
    """A stand-in loop guard: "go a" is a loop."""

    def loops(self, line: str) -> bool:
        return line.endswith("go a")


def test_where_there_is_no_way_out_the_best_token_that_closes_no_loop_is_asked_for():
    """Outside free text the looping token is banned and the server asked again: its next best is taken."""
    choices = Grammar({"root": seq("go ", alt("ab", "ac", "b"), "\n")})
    asked = []

    def prefers_a(context, grammar, limit, banned):  # a, then b, c, newline and space, as the grammar allows
        asked.append(list(banned))
        return next([ord(c)] for c in "abc\n " if ord(c) not in banned and Matcher(grammar).advance(c)), None

    line = LineRequests(CONTEXT, choices, Sampling(loop_guard=NoGoA()), prefers_a, spell, text_of).write(100)
    assert line.text == "go b\n" and line.loops == 1
    # the space that ends the forced "go " is the model's; then a, banned, and b
    assert asked == [[], [], [ord("a")], []]


END = 7  # the stand-in model's end of sequence


class Reporting:
    """A server that reports, for each token it writes, the unconstrained model's likeliest tokens: it writes
    ``line``, where its model ranks ``END`` as it is told (a log-probability per position, else far below)."""

    def __init__(self, line: str, end_at: dict[int, float]):
        self.line, self.end_at = line, end_at

    def __call__(self, context, grammar, limit, banned):
        at = len(context) - len(CONTEXT)
        tokens = [ord(c) for c in self.line[at:]][:limit]
        probs = []
        for k, token in enumerate(tokens):
            top = sorted([(token, -1.0), (ord("z"), -0.5), (END, self.end_at.get(at + k, -9.0))], key=lambda t: -t[1])
            probs.append((-1.0, top))
        return tokens, probs


def test_where_a_server_reports_the_model_would_rather_end_it_ends_and_each_choice_is_measured():
    """The end of sequence is the model's choice through a server too: greedy, where it is likelier than the
    token the grammar let the server write (as in-process). Each token the model chose is measured: its
    likeliest token (here always a "z" the grammar refuses) refused, and the chosen token's log-probability."""
    server = Reporting("    PutObject('Fridge', 'Bowl')\n", {15: -0.2})
    line = LineRequests(CONTEXT, PUT, Sampling(), server, spell, text_of, end_tokens=frozenset({END})).write(100)
    assert line.stop == "eos" and line.text == "    PutObject('"  # the quote chosen, then the end, not the F
    assert (line.choices, line.refused) == (2, 1) and line.logprob == pytest.approx(-1.0 - 0.2)
    whole = LineRequests(CONTEXT, PUT, Sampling(), Reporting(server.line, {}), spell, text_of,
                         end_tokens=frozenset({END})).write(100)
    assert whole.stop == "line" and (whole.choices, whole.refused) == (3, 3)  # the quote, the F, the newline
    unreported = LineRequests(CONTEXT, PUT, Sampling(), Scripted(server.line), spell, text_of,
                              end_tokens=frozenset({END})).write(100)
    assert unreported.stop == "line" and unreported.choices == 0
    sampled = LineRequests(CONTEXT, PUT, Sampling(temperature=1.0), server, spell, text_of,
                           end_tokens=frozenset({END})).write(100)
    assert sampled.stop == "line"  # sampling through a server cannot tell when the model drew the end
