"""The decoding loop (planner/decoding/loop.py) on a model small enough to read: one token per character, logits
that say which character the model likes next, and a grammar engine that follows the planner's own matcher. What
a real backend adds (llama.cpp's grammar, its cache) is tested with real models in test_llamacpp.py."""

from __future__ import annotations

import copy
import string
from collections.abc import Callable, Sequence

import numpy as np

from smartllm_local.planner.decoding.first_bytes import FirstBytes
from smartllm_local.planner.decoding.grammar import Grammar, alt, chars, rep, seq
from smartllm_local.planner.decoding.loop import generate
from smartllm_local.planner.decoding.matcher import Matcher
from smartllm_local.planner.decoding.sampling import Sampling

#: One token per character, more than the 64 the loop looks at first; the end of sequence last.
ALPHABET = "\nabc#" + "".join(sorted(set(string.printable) - set("\nabc#\t\r\x0b\x0c")))
END = len(ALPHABET)


class CharGrammar:
    """A grammar engine over the characters' tokens: the planner's matcher, so it never disagrees with it."""

    name = "the test's grammar"

    def __init__(self, grammar: Grammar):
        self.matcher = Matcher(grammar)
        self.asked: list[int] = []  # how many tokens each mask asked about

    def admits(self, token: int) -> bool:
        if token == END:
            return self.matcher.accepting
        return copy.copy(self.matcher).advance(ALPHABET[token])

    def mask(self, logits: np.ndarray, ids: np.ndarray | None = None) -> np.ndarray:
        ids = np.arange(len(logits)) if ids is None else ids
        self.asked.append(len(ids))
        return np.array([s if self.admits(int(t)) else -np.inf for t, s in zip(ids, logits)], dtype=np.float32)

    def accept(self, token: int) -> bool:
        return self.matcher.advance(ALPHABET[token])

    def close(self) -> None:
        pass


class CharModel:
    """A model that likes ``likes(text so far)`` best (logit 2), then the characters in the alphabet's order (logits
    from 0 down), the end of sequence least (-1)."""

    n_ctx = 1000
    n_vocab = END + 1
    end_tokens = frozenset({END})

    def __init__(self, likes: Callable[[str], str], by_first_byte: bool = True):
        self.likes, self.tokens, self.batches, self.grammars = likes, [], [], []
        self.index = FirstBytes(self.token_bytes, self.n_vocab) if by_first_byte else None

    def tokenize_continuation(self, text: str) -> list[int]:
        return [ALPHABET.index(c) for c in text]

    def token_bytes(self, token: int) -> bytes:
        return b"" if token == END else ALPHABET[token].encode()

    def sync(self, context: Sequence[int]) -> None:
        self.tokens = list(context)

    def evaluate(self, tokens: list[int]) -> None:
        self.tokens += tokens
        self.batches.append(list(tokens))

    def next_logits(self) -> np.ndarray:
        logits = -np.arange(self.n_vocab, dtype=np.float32) / self.n_vocab
        logits[END] = -1.0
        logits[ALPHABET.index(self.likes(self.text()))] = 2.0
        return logits

    def text(self) -> str:
        return b"".join(self.token_bytes(t) for t in self.tokens).decode()

    def constrain(self, grammar: Grammar) -> CharGrammar:
        self.grammars.append(CharGrammar(grammar))
        return self.grammars[-1]

    def first_bytes(self) -> FirstBytes | None:
        return self.index


def test_forced_text_goes_in_one_batch_but_its_last_token_which_the_model_writes():
    model = CharModel(lambda text: "'" if text.endswith("GoTo(") else "a")
    grammar = Grammar({"root": seq("GoTo('", rep(chars("ab"), 1, 4), "')\n")})
    out = generate(model, [0], grammar=grammar, max_tokens=20, sampling=Sampling())
    assert model.batches[0] == model.tokenize_continuation("GoTo(")  # forced, in one batch
    assert model.batches[1] == model.tokenize_continuation("'")  # the model's own token (healing)
    assert out.text == "GoTo('aaaa')\n" and out.stop == "line"
    assert out.forced == len("GoTo(") + len("')") and out.forced + out.choices == len(out.tokens)
    unaligned = CharModel(model.likes)
    generate(unaligned, [0], grammar=grammar, max_tokens=20, sampling=Sampling(aligned=False))
    assert unaligned.batches[0] == model.tokenize_continuation("GoTo('")  # written whole


def test_the_loop_guard_ends_free_text_by_the_grammars_way_out():
    model = CharModel(lambda text: "a")
    grammar = Grammar({"root": seq("# ", rep(chars("ab"), 0, 40), "\n")})
    out = generate(model, [0], grammar=grammar, max_tokens=60, sampling=Sampling())
    assert out.text == "# " + "a" * 8 + "\n" and out.loops == 1  # a ninth "a" would loop
    unguarded = generate(CharModel(model.likes), [0], grammar=grammar, max_tokens=60,
                         sampling=Sampling(loop_guard=None))
    assert unguarded.text == "# " + "a" * 40 + "\n" and unguarded.loops == 0


def test_without_a_way_out_the_guard_takes_the_best_token_that_closes_no_loop():
    out = generate(CharModel(lambda text: "a"), [0], grammar=None, max_tokens=9, sampling=Sampling())
    assert out.text == "a" * 8 + "\n" and out.loops == 1  # "\n": the likeliest after "a"


def test_the_bend_counts_the_choices_whose_likeliest_token_the_grammar_refused():
    model = CharModel(lambda text: "a")
    grammar = Grammar({"root": seq(rep(chars("bc"), 3, 3), "\n")})
    out = generate(model, [0], grammar=grammar, max_tokens=10, sampling=Sampling())
    assert out.text == "bbb\n" and out.forced == 0
    assert out.choices == 4 and out.refused == 4  # "a" every time, never admitted
    logits = model.next_logits().astype(np.float64)
    logprob = logits - np.log(np.exp(logits).sum())  # unconstrained, the same at every step
    assert np.isclose(out.logprob, 3 * logprob[ALPHABET.index("b")] + logprob[ALPHABET.index("\n")])
    free = generate(CharModel(model.likes), [0], grammar=None, max_tokens=3, sampling=Sampling())
    assert free.text == "aaa" and free.choices == 3 and free.refused == 0
    assert np.isclose(free.logprob, 3 * logprob[ALPHABET.index("a")])


def test_the_model_ends_where_the_end_is_its_likeliest_token():
    model = CharModel(lambda text: "b")
    model.next_logits = lambda: np.eye(END + 1, dtype=np.float32)[END]  # the end is likeliest from the start
    grammar = Grammar({"root": seq(rep(chars("ab"), 1, 4), "\n")})
    out = generate(model, [0], grammar=grammar, max_tokens=10, sampling=Sampling())
    assert out.stop == "eos" and out.text == "" and out.choices == 1
    strict = generate(model, [0], grammar=grammar, max_tokens=10, sampling=Sampling(aligned=False))
    assert strict.stop == "line" and strict.text  # unaligned: the model ends only where the grammar may


def test_a_whole_vocabulary_mask_asks_the_engine_only_about_tokens_that_begin_with_a_character_admitted_next():
    # The model likes "a", then the alphabet in order: its 64 likeliest are all refused where the grammar admits
    # only characters from the end of the alphabet, so each choice masks the whole vocabulary.
    grammar = Grammar({"root": seq(rep(chars("~}"), 2, 2), alt("|", "{"), "\n")})
    late = [c for c in ALPHABET if ALPHABET.index(c) > 64]
    assert set("~}|{") <= set(late)
    outputs = {}
    for narrowed in (True, False):
        for sampling in (Sampling(), Sampling(temperature=1.0, seed=3)):
            model = CharModel(lambda text: "a", by_first_byte=narrowed)
            out = generate(model, [0], grammar=grammar, max_tokens=10, sampling=sampling)
            outputs[narrowed, sampling.temperature] = out.text, out.logprob
            whole = [n for n in model.grammars[0].asked if n != 64]  # (greedy asks about its 64 likeliest first)
            # "~}" or "|{", and the end of sequence (a token without text), where narrowed
            assert len(whole) >= 3 and all(n == (3 if narrowed else model.n_vocab) for n in whole[:3])
    assert outputs[True, 0.0] == outputs[False, 0.0] and outputs[True, 1.0] == outputs[False, 1.0]
    assert outputs[True, 0.0][0] == "}}{\n"  # the best admitted: the latest characters are the model's least liked


def test_the_vocabulary_by_first_byte_keeps_tokens_without_text_and_reads_a_characters_first_byte():
    pieces = [b"", b"ab", b"a", b"b", "\u00e9t\u00e9".encode(), b"\xc3", b"\xa9"]
    index = FirstBytes(lambda t: pieces[t], len(pieces))
    assert sorted(index.starting_with("a").tolist()) == [0, 1, 2]
    assert sorted(index.starting_with({"\u00e9", "b"}).tolist()) == [0, 3, 4, 5]  # "é" begins with byte 0xc3
    assert index.starting_with(()).tolist() == [0]
