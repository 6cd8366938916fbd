"""The grammar model: emission (GBNF, Lark), checks, membership, sampling, length bounds."""

from __future__ import annotations

import random

import llguidance
import pytest
from hypothesis import given
from hypothesis import strategies as st

from smartllm_local.planner.decoding.grammar import Grammar, GrammarError, Ref, alt, chars, opt, rep, seq


def test_gbnf_escapes_quotes_backslashes_newlines_and_class_punctuation():
    """A hex digit right after an escape is escaped too (XGrammar would read it as part of the escape), and
    characters past ASCII are written as themselves."""
    g = Grammar({"root": seq('say "hi"\\', "\n", rep(chars("-]^[a"), 1, 2), opt("x"), '"F1g', "é—")})
    text = g.to_gbnf()
    assert text == ('root ::= "say \\x22hi\\x22\\x5C" "\\n" [\\x2D\\x5B\\x5D\\x5E\\x61]{1,2} "x"? '
                    '"\\x22\\x46\\x31g" "é—"\n')
    assert g.matches('say "hi"\\\n-]x"F1gé—') and g.matches('say "hi"\\\n^"F1gé—') and not g.matches('say "hi"\\\n')


def test_rules_are_emitted_reachable_only_and_root_first():
    g = Grammar({"unused": "zzz", "word": alt("a", "b"), "root": seq(Ref("word"), "!")})
    assert g.to_gbnf().splitlines() == ['root ::= word "!"', 'word ::= "a" | "b"']


@pytest.mark.parametrize("rules, message", [
    ({"word": "a"}, "root"),
    ({"root": Ref("missing")}, "undefined rule"),
    ({"root": Ref("loop"), "loop": seq("a", Ref("loop"))}, "must not recurse"),
    ({"root": "a", "Bad_Name": "b"}, "rule name"),
])
def test_malformed_grammars_are_refused(rules, message):
    with pytest.raises(GrammarError, match=message):
        Grammar(rules)


def test_bad_building_blocks_are_refused():
    with pytest.raises(GrammarError):
        rep("a", 2, 1)
    with pytest.raises(GrammarError):
        chars("\n")
    with pytest.raises(GrammarError):
        alt()


def test_samples_are_members_and_never_longer_than_the_bound():
    g = Grammar({
        "item": alt("apple", "fig", seq("k", rep(chars("xyz"), 0, 3))),
        "root": seq(Ref("item"), rep(seq(", ", Ref("item")), 0, 4), "\n"),
    })
    rng = random.Random(0)
    bound = g.max_length()
    assert bound == len("apple") * 1 + 4 * (2 + 5) + 1
    for _ in range(300):
        sample = g.sample(rng)
        assert g.matches(sample) and len(sample) <= bound
    assert not g.matches("apple, pear\n")


def test_llguidance_accepts_the_gbnf_form():
    g = Grammar({"obj": alt("'Apple'", "'Fridge'"), "root": seq("PutObject(", Ref("obj"), ")\n")})
    assert llguidance.LLMatcher.validate_grammar(llguidance.grammar_from("gbnf", g.to_gbnf())) == ""


def test_the_matcher_follows_text_and_knows_what_is_forced():
    from smartllm_local.planner.decoding.matcher import Matcher

    g = Grammar({"obj": alt("'Apple'", "'Fridge'"), "root": seq("    PutObject(", Ref("obj"), ", 'Bowl')\n")})
    m = Matcher(g)
    assert m.forced() == "    PutObject('"
    assert m.advance("    PutObject('") and m.forced() == ""
    assert not m.advance("B") and m.advance("Fri")
    assert m.forced() == "dge', 'Bowl')\n"
    assert m.advance("dge', 'Bowl')\n") and m.accepting and m.forced() == ""
    optional = Matcher(Grammar({"root": alt("", "abc\n")}))
    assert optional.accepting and optional.forced() == ""


def test_matchers_of_one_grammar_walk_it_apart():
    """Matchers of one grammar share its automaton (built once) but not where they stand in it."""
    from smartllm_local.planner.decoding.matcher import Matcher

    g = Grammar({"root": seq("Go(", alt("'Apple'", "'Fridge'"), ")\n")})
    first, second = Matcher(g), Matcher(g)
    assert first.advance("Go('Fri") and not second.advance("Go('B")
    assert second.forced() == "Go('" and first.forced() == "dge')\n"
    assert second.advance("Go('Apple')\n") and second.accepting and not first.accepting


def test_a_grammar_that_admits_one_string_says_which():
    """What the writer carries as forced text: a line with one way to write it, whatever nodes spell it."""
    one = Grammar({"robot": alt("robot_list[0]"), "root": seq("    Go(", Ref("robot"), ", ", rep("'", 1, 1), chars("A"),
                                                              "pple')\n")})
    assert one.only() == "    Go(robot_list[0], 'Apple')\n"
    assert Grammar({"root": alt("ab", seq("a", "b"))}).only() == "ab"
    for several in (alt("a", "b"), opt("a"), chars("ab"), seq("x", rep("y", 0, 2)), alt("a", chars("ab"))):
        assert Grammar({"root": several}).only() is None


# A grammar with every kind of node: literals, classes, references, nullable items in sequences, nested and
# bounded repetitions, alternatives that share their starts.
_WORDS = Grammar({
    "name": alt("ab", "abc", seq("b", rep(chars("abc"), 0, 2))),
    "list": seq(Ref("name"), rep(seq(opt(" "), ",", Ref("name")), 0, 3)),
    "root": seq(opt("c"), alt(Ref("list"), seq("a", rep(chars("ab "), 2, 4))), opt(seq(" ", rep("ca", 1, 2))), "\n"),
})


_SHORT = ["", *(a + b for a in " abc,\n" for b in ("", *" abc,\n"))]  # every text of up to two characters


@given(st.integers(0, 2**32), st.text(alphabet="abc ,\n", max_size=12))
def test_after_a_prefix_a_grammar_admits_exactly_what_may_follow_it(seed, noise):
    """The derivative's defining equation: after every prefix of a line, a text follows exactly when the
    prefix and the text make a line (texts that do and texts that almost do); one that names the only text that
    may follow names the rest of the line."""
    from smartllm_local.planner.decoding.matcher import Matcher

    line = _WORDS.sample(random.Random(seed))
    for cut in range(len(line) + 1):
        prefix, rest = line[:cut], line[cut:]
        after = _WORDS.after(prefix)
        for text in (rest, noise, rest + noise, noise + rest, *(x + y for x in _SHORT for y in ("", rest, rest[1:]))):
            assert after.matches(text) == _WORDS.matches(prefix + text), (prefix, text)
        assert after.only() in (None, rest)  # where one string may follow, it is the rest of this line
        if not Matcher(_WORDS).advance(prefix + noise):
            with pytest.raises(GrammarError, match="does not begin"):
                _WORDS.after(prefix + noise)


def test_after_real_stage_lines_llama_cpp_reads_the_grammar_and_forces_the_same_text(smollm2):
    """Every line of a few tasks' three stages, written by adversarial writers, cut at every point: what the
    rest of the line must be is the same in the grammar after the cut as in the whole grammar, and
    llama.cpp's grammar engine reads the grammar a server is sent."""
    from smartllm_local.planner.decoding.matcher import Matcher
    from tests.planner.constraints import test_guarantees as guarantees

    lines = guarantees.collect_lines(random.Random(7), ["kitchen-01", "living-01", "bathroom-01"])
    assert len(lines) > 100
    for grammar, line in lines:
        for cut in range(0, len(line) + 1, 5):
            after = grammar.after(line[:cut])
            whole = Matcher(grammar)
            assert whole.advance(line[:cut]) and after.matches(line[cut:])
            assert Matcher(after).forced() == whole.forced()
        smollm2.constrain(grammar.after(line[: len(line) // 2])).close()
