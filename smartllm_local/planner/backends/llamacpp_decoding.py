"""How llama.cpp's backends choose each token: one decoding loop, for one sequence or for a lane among several.

llama-cpp-python's sampler chain applies a grammar to the whole vocabulary at
every step: ~60 ms per token for Gemma-3's 262k tokens on two cores. Here the
grammar is asked first only about the likeliest tokens: greedy decoding takes
the likeliest token if the grammar admits it, else the best of the top 64 that
it admits (the same token a full mask would give, since any admitted token
outside the top 64 scores lower; finding the 64 costs 0.5 ms a step on
SmolLM2's vocabulary and 2.8 ms on Gemma-3's, so it is done only then), and
sampling draws from the full distribution and keeps the draw if the grammar
admits it (rejection sampling, which gives exactly the masked distribution).
Only when that fails is the full vocabulary masked.

Grammars are checked by llama.cpp before use: ``llama_sampler_init_grammar``
returns NULL for a bad one (llama-cpp-python 0.3.36 does not check, and a bad
grammar would crash the process at the first token).

The text of generated tokens is their bytes, decoded as they come (a
character split across tokens is held back until complete), and it is
followed through the planner's own grammar: where that grammar does not
allow what llama.cpp's let through, or llama.cpp's refuses text the planner's
grammar forces, the two disagree and generation stops with an error.

What differs between a backend of one sequence and a lane of several (see :mod:`.lanes`) is only how the
context gets into the key/value cache and where the logits come from: the hooks :meth:`_sync`,
:meth:`_evaluate` and :meth:`_logits`. Every decision on a token is made here, the same for both.
"""

from __future__ import annotations

import codecs
import ctypes
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ...errors import GrammarMismatchError, ModelError
from ..decoding.grammar import Grammar, GrammarError
from ..decoding.matcher import Matcher
from .base import END_RANK, Generated, Sampling, may_end
from .repetition import TRIES, current_line, draw

_TOP = END_RANK  # the candidates looked at before the whole vocabulary is masked


class LlamaDecoding:
    """The decoding loop and its token choice, mixed into a llama.cpp backend and into each lane's view.

    A subclass calls :meth:`_init_decoding` once it knows its vocabulary, and provides ``_piece`` (a token's bytes),
    ``tokenize_continuation`` and the cache hooks below. The buffers and the end-of-sequence setting are per object:
    lanes decoding at once in several threads never share them."""

    _lib: Any
    _vocab: Any
    n_ctx: int
    n_vocab: int

    def _init_decoding(self, eog: np.ndarray) -> None:
        self._eog = eog
        self.end_tokens = frozenset(int(t) for t in np.flatnonzero(eog))  # llama.cpp's end-of-generation
        self._full = np.zeros(self.n_vocab, dtype=[("id", np.intc), ("logit", np.single), ("p", np.single)])
        self._few = np.zeros(_TOP, dtype=self._full.dtype)
        self._ends = True  # whether the end of sequence is always admitted (Sampling.aligned)

    # hooks
    def _piece(self, token: int, special: bool = False) -> bytes:
        raise NotImplementedError

    def tokenize_continuation(self, text: str) -> list[int]:
        raise NotImplementedError

    def _sync(self, context: Sequence[int]) -> None:
        """Make the cache hold ``context`` and the logits be those of its last token."""
        raise NotImplementedError

    def _evaluate(self, tokens: list[int]) -> None:
        """Evaluate ``tokens`` after what the cache holds; the logits become those of the last."""
        raise NotImplementedError

    def _logits(self) -> np.ndarray:
        """The logits of the last token evaluated (a copy)."""
        raise NotImplementedError

    # -------------------------------------------------------------- grammars

    def _grammar_sampler(self, grammar: Grammar):
        sampler = self._lib.llama_sampler_init_grammar(self._vocab, grammar.to_gbnf().encode(), b"root")
        if not sampler:
            raise GrammarError("llama.cpp rejected a grammar:\n" + grammar.to_gbnf())
        return sampler

    def _apply(self, sampler, buffer: np.ndarray, count: int) -> None:
        array = self._lib.llama_token_data_array(
            data=buffer.ctypes.data_as(self._lib.llama_token_data_p), size=count, selected=-1, sorted=False
        )
        self._lib.llama_sampler_apply(sampler, ctypes.byref(array))

    def _allowed(self, sampler, token: int) -> bool:
        self._few[0] = (token, 0.0, 0.0)
        self._apply(sampler, self._few, 1)
        return bool(np.isfinite(self._few["logit"][0]))

    def _masked(self, sampler, logits: np.ndarray) -> np.ndarray:
        self._full["id"] = np.arange(self.n_vocab, dtype=np.intc)
        self._full["logit"] = logits
        self._apply(sampler, self._full, self.n_vocab)
        masked = np.full(self.n_vocab, -np.inf, dtype=np.float32)
        masked[self._full["id"]] = self._full["logit"]
        if self._ends:  # the end of sequence is the model's to choose (see END_RANK)
            for end in self.end_tokens:
                if may_end(logits, end):
                    masked[end] = logits[end]
        return masked

    def _pick(self, logits: np.ndarray, sampler, sampling: Sampling, rng: np.random.Generator,
              avoid: Callable[[int], bool] | None = None) -> int:
        """The next token, greedy or sampled, among those the grammar admits and, where any of them is
        left, those ``avoid`` does not refuse. The end of sequence is always admitted: where the model
        ends, the planner completes the output (see :mod:`..decoding.writer`)."""
        if not np.isfinite(logits[int(np.argmax(logits))]):
            raise ModelError("the model's scores are not numbers (NaN or infinite logits): its weights, or the build "
                             "that runs them, are broken (on a GPU, see whether --n-gpu-layers 0 runs it)")
        if sampling.temperature <= 0:
            best = int(np.argmax(logits))
            if (self._admits(sampler, best)) and not (avoid and avoid(best)):
                return best
            top = np.argpartition(-logits, _TOP)[:_TOP]
            top = top[np.argsort(-logits[top], kind="stable")]
            self._few["id"] = top
            self._few["logit"] = logits[top]
            if sampler is not None:
                self._apply(sampler, self._few, _TOP)
                if self._ends:
                    self._few["logit"][self._eog[top]] = logits[top][self._eog[top]]
            admitted = self._few["id"][np.isfinite(self._few["logit"])]
            if not len(admitted) or (avoid and len(admitted) < TRIES and all(avoid(int(t)) for t in admitted)):
                masked = self._masked(sampler, logits)
                if not np.isfinite(masked).any():
                    raise GrammarError("the grammar admits no token here")
                admitted = np.argsort(-masked, kind="stable")[: int(np.isfinite(masked).sum())]
            # The best admitted token that ``avoid`` does not refuse, among the best TRIES; else the best.
            return next((int(t) for t in admitted[:TRIES] if not (avoid and avoid(int(t)))), int(admitted[0]))
        scaled = logits.astype(np.float64) / sampling.temperature
        probs = np.exp(scaled - scaled.max())
        probs /= probs.sum()
        token = int(rng.choice(self.n_vocab, p=probs))
        if self._admits(sampler, token) and not (avoid and avoid(token)):
            return token
        masked = self._masked(sampler, logits).astype(np.float64) / sampling.temperature if sampler else scaled
        if not np.isfinite(masked).any():
            raise GrammarError("the grammar admits no token here")
        return draw(np.exp(masked - masked[np.isfinite(masked)].max()), rng, avoid, TRIES)

    def _admits(self, sampler, token: int) -> bool:
        return sampler is None or (self._ends and bool(self._eog[token])) or self._allowed(sampler, token)

    # ------------------------------------------------------------ generation

    def generate(
        self,
        context: Sequence[int],
        *,
        grammar: Grammar | None,
        max_tokens: int,
        sampling: Sampling,
        stop: Sequence[str] = (),
        rng: np.random.Generator | None = None,
        lines: int = 1,
    ) -> Generated:
        """See :meth:`.base.Backend.generate`."""
        rng = rng or np.random.default_rng(sampling.seed)
        if len(context) + max_tokens > self.n_ctx:
            max_tokens = self.n_ctx - len(context) - 1
        self._sync(context)
        self._ends = sampling.aligned
        sampler = self._grammar_sampler(grammar) if grammar is not None else None
        matcher = Matcher(grammar) if grammar is not None else None
        out = Generated([], "", "length")
        decoder = codecs.getincrementaldecoder("utf-8")("replace")
        try:
            while len(out.tokens) < max_tokens:
                new = self._next_tokens(out, matcher, sampler, sampling, rng)
                if new is None:
                    out.text += decoder.decode(b"", final=True)
                    out.stop = "eos"
                    return out
                self._evaluate(new)
                piece = decoder.decode(b"".join(self._piece(t) for t in new))
                if matcher is not None and not matcher.advance(piece):
                    raise GrammarMismatchError(out.text + piece, "llama.cpp's grammar let the model write it, "
                                               "the planner's grammar does not allow it")
                out.text += piece
                if sampler is not None and out.text.count("\n") >= lines:
                    out.stop = "line"
                    return out
                for s in stop:
                    if s in out.text:
                        out.text, out.stop = out.text[: out.text.index(s)], "stop"
                        return out
            out.text += decoder.decode(b"", final=True)
            return out
        finally:
            if sampler is not None:
                self._lib.llama_sampler_free(sampler)

    def _next_tokens(self, out: Generated, matcher: Matcher | None, sampler, sampling: Sampling,
                     rng: np.random.Generator) -> list[int] | None:
        """The tokens to write next, accepted by llama.cpp's grammar and counted in ``out``: text the grammar
        forces (several at once), or the one token the model chooses from the last logits; None where the model
        ends the sequence."""
        guard = sampling.loop_guard
        new = self._forced_tokens(matcher.forced(), sampler, heal=sampling.aligned) if matcher else []
        forced = len(new)
        if not new:
            logits = self._logits()
            token = self._pick(logits, sampler, sampling, rng)
            line = current_line(out.text)
            if guard is not None and guard.loops(line + self._text(token)):
                # A loop: end the free text it runs in (the grammar's shortest way on), or else
                # take the best token that does not close the loop.
                new = self._forced_tokens(matcher.shortest_way(), sampler, way=True) if matcher else []
                forced = len(new)
                token = token if new else self._pick(
                    logits, sampler, sampling, rng, lambda t: guard.loops(line + self._text(t)))
                out.loops += 1
            if not new:
                self._measure(out, logits, token, sampler)
        if not new:
            if self._eog[token]:
                return None
            if sampler is not None:
                self._lib.llama_sampler_accept(sampler, token)
            new = [token]
        out.tokens.extend(new)
        out.forced += forced
        return new

    def _measure(self, out: Generated, logits: np.ndarray, token: int, sampler) -> None:
        """How far the grammar bent the model at a token it chose: whether its likeliest token was refused,
        and the chosen token's log-probability under the unconstrained model."""
        best = int(np.argmax(logits))
        out.choices += 1
        out.refused += best != token and not self._admits(sampler, best)
        top = float(logits[best])
        out.logprob += float(logits[token]) - top - float(np.log(np.exp(logits - top, dtype=np.float64).sum()))

    def _forced_tokens(self, forced: str, sampler, *, way: bool = False, heal: bool = True) -> list[int]:
        """The tokens of text the planner's grammar forces, all in one batch, accepted by llama.cpp's grammar;
        with ``heal``, all but the last, which the model writes itself (it may run on into what follows: token
        healing). A loop guard's ``way`` out is written whole.

        Each is checked before llama.cpp accepts it: accepting a token its grammar refuses aborts the process.
        """
        if len(forced) < 2 and not way:  # one character costs no more sampled than forced
            return []
        tokens = self.tokenize_continuation(forced)
        if heal and not way:
            tokens = tokens[:-1]
        for token in tokens:
            if not self._allowed(sampler, token):
                raise GrammarMismatchError(forced, "the planner's grammar forces it, llama.cpp's grammar refuses it")
            self._lib.llama_sampler_accept(sampler, token)
        return tokens

    def _text(self, token: int) -> str:
        return self._piece(token).decode("utf-8", errors="replace")
