"""What llama.cpp's backends give the decoding loop (:mod:`..decoding.loop`): llama.cpp's grammar as a token mask,
and the loop itself, for one sequence or for a lane among several.

llama-cpp-python's sampler chain applies a grammar to the whole vocabulary at every step; here its grammar
sampler is asked about the tokens the loop names (the likeliest first), which is what makes greedy decoding
cheap on a large vocabulary (see :mod:`..decoding.loop`).

Grammars are checked by llama.cpp before use: ``llama_sampler_init_grammar`` returns NULL for a bad one
(llama-cpp-python 0.3.36 does not check, and a bad grammar would crash the process at the first token); and a
token is checked before the sampler accepts it: accepting one its grammar refuses aborts the process.

Both a backend of one sequence and a lane of several (see :mod:`.lanes`) evaluate lazily: the tokens the loop
adds, and what a context that goes on from them adds, wait until logits are next asked for, so that a line's last
token and the next line's forced text go into one batch, which carries drafts from the context (:mod:`.drafts`),
kept where the model then chooses them. What differs between the two is only how a batch reaches llama.cpp and
how drafts leave the cache: the hooks of :class:`LlamaDecoding`.
"""

from __future__ import annotations

import ctypes
import threading
from collections.abc import Sequence
from typing import Any

import numpy as np

from ...errors import ModelError
from ..decoding import loop
from ..decoding.first_bytes import FirstBytes
from ..decoding.grammar import Grammar, GrammarError
from ..decoding.sampling import END_RANK, Generated, Sampling
from .base import shared_prefix

_DATA = [("id", np.intc), ("logit", np.single), ("p", np.single)]  # llama_token_data
_MAKING = threading.Lock()


def fill_batch(batch: Any, tokens: Sequence[int], start: int, *, seq: int = 0, logits_from: int = 0,
               at: int = 0) -> int:
    """Put ``tokens`` into the ``llama_batch`` from its slot ``at``, at positions from ``start`` of sequence ``seq``,
    logits asked for after the ``logits_from``-th token on; the next free slot."""
    for i, token in enumerate(tokens):
        slot = at + i
        batch.token[slot], batch.pos[slot], batch.n_seq_id[slot] = token, start + i, 1
        batch.seq_id[slot][0], batch.logits[slot] = seq, i >= logits_from
    return at + len(tokens)


class LlamaGrammar:
    """A grammar compiled by llama.cpp (its grammar sampler), asked about the tokens the loop names."""

    name = "llama.cpp's grammar"

    def __init__(self, lib: Any, vocab: Any, n_vocab: int, grammar: Grammar):
        self._lib, self._n_vocab = lib, n_vocab
        self._sampler = lib.llama_sampler_init_grammar(vocab, grammar.to_gbnf().encode(), b"root")
        if not self._sampler:
            raise GrammarError("llama.cpp rejected a grammar:\n" + grammar.to_gbnf())
        self._few = np.zeros(END_RANK, dtype=_DATA)  # grows to the most tokens asked about at once
        self._full: np.ndarray | None = None  # the whole vocabulary's buffer, made when first needed
        self._admitted = -1  # a token just found admitted, at the grammar's state now (accepted without asking again)

    def _apply(self, buffer: np.ndarray, count: int) -> None:
        array = self._lib.llama_token_data_array(
            data=buffer.ctypes.data_as(self._lib.llama_token_data_p), size=count, selected=-1, sorted=False)
        self._lib.llama_sampler_apply(self._sampler, ctypes.byref(array))

    def admits(self, token: int) -> bool:
        self._few[0] = (token, 0.0, 0.0)
        self._apply(self._few, 1)
        admitted = bool(np.isfinite(self._few["logit"][0]))
        if admitted:
            self._admitted = token
        return admitted

    def mask(self, logits: np.ndarray, ids: np.ndarray | None = None) -> np.ndarray:
        if ids is not None:
            if len(ids) > len(self._few):
                self._few = np.zeros(len(ids), dtype=_DATA)
            self._few["id"][: len(ids)], self._few["logit"][: len(ids)] = ids, logits
            self._apply(self._few, len(ids))
            return self._few["logit"][: len(ids)].copy()
        if self._full is None:
            self._full = np.zeros(self._n_vocab, dtype=_DATA)
        self._full["id"] = np.arange(self._n_vocab, dtype=np.intc)
        self._full["logit"] = logits
        self._apply(self._full, self._n_vocab)
        masked = np.full(self._n_vocab, -np.inf, dtype=np.float32)
        masked[self._full["id"]] = self._full["logit"]
        return masked

    def accept(self, token: int) -> bool:
        if token != self._admitted and not self.admits(token):
            return False
        self._admitted = -1
        self._lib.llama_sampler_accept(self._sampler, token)
        return True

    def close(self) -> None:
        self._lib.llama_sampler_free(self._sampler)


class LlamaDecoding:
    """The decoding loop's model (:class:`..decoding.loop.TokenModel`), mixed into a llama.cpp backend and into each
    lane's view. A subclass calls :meth:`_init_decoding` once it knows its vocabulary, and provides ``_piece`` (a
    token's bytes), ``tokenize_continuation`` and the cache hooks below."""

    _lib: Any
    _vocab: Any
    n_ctx: int
    n_vocab: int

    def _init_decoding(self, end_tokens: frozenset[int], drafting: bool) -> None:
        self.end_tokens = end_tokens  # llama.cpp's end-of-generation tokens
        self._first_bytes: FirstBytes | None = None
        self._drafting = drafting  # off: each token evaluated as it is added, alone or with those added with it
        self._pending: list[int] = []  # the context's tokens after those the cache holds, not evaluated yet
        self._rows: np.ndarray | None = None  # logits after the context's last token, then after each draft

    # hooks
    def _piece(self, token: int, special: bool = False) -> bytes:
        raise NotImplementedError

    def tokenize_continuation(self, text: str) -> list[int]:
        raise NotImplementedError

    def _held(self) -> list[int]:
        """The context the cache holds (the drafts after it not counted)."""
        raise NotImplementedError

    def _drafts(self) -> list[int]:
        """The drafts the cache holds after the context."""
        raise NotImplementedError

    def _keep_drafts(self, count: int) -> None:
        """The first ``count`` drafts are the context's from now on."""
        raise NotImplementedError

    def _drop_drafts(self) -> None:
        """Take the drafts out of the cache (the model chose otherwise)."""
        raise NotImplementedError

    def _flush(self, drafts: bool) -> None:
        """Evaluate the pending tokens, with ``drafts`` after them where the context suggests any, and set the rows of
        logits."""
        raise NotImplementedError

    def _restart(self, context: list[int], common: int) -> None:
        """Make the cache hold ``context``, of which it holds the first ``common`` tokens and then others (or
        nothing)."""
        raise NotImplementedError

    # lazy evaluation
    def sync(self, context: Sequence[int]) -> None:
        """Make the cache hold ``context``: what goes on from the context it holds is evaluated when logits are next
        asked for, in one batch with the tokens the loop adds before then; anything else as :meth:`_restart` has
        it."""
        context = self._fitted(context)
        held = self._held()
        common = shared_prefix(held, context)
        if held and common == len(held) and (len(context) > common or self._rows is not None):
            self._pending = self._pending[:shared_prefix(self._pending, context[common:])]
            self.evaluate(context[common + len(self._pending):])
        else:
            self._restart(context, common)

    def _fitted(self, context: Sequence[int]) -> list[int]:
        """``context`` as a list, or a clear error where it does not fit the cache."""
        if len(context) >= self.n_ctx:
            raise ModelError(f"the context ({len(context)} tokens) does not fit n_ctx={self.n_ctx}")
        return list(context)

    def evaluate(self, tokens: list[int]) -> None:
        """Add ``tokens`` to the context: those that follow the drafts the cache holds cost nothing, the rest are
        evaluated when logits are next asked for (at once without drafts)."""
        if (ahead := self._drafts()) and not self._pending and self._rows is not None:
            kept = shared_prefix(ahead, tokens)
            self._keep_drafts(kept)
            self._rows, tokens = self._rows[kept:], tokens[kept:]
        if tokens:
            self._without_drafts()
            self._pending.extend(tokens)
            if not self._drafting:
                self._flush(drafts=False)

    def _without_drafts(self) -> None:
        """Take the drafts out of the cache, and their rows of logits."""
        if self._drafts():
            self._drop_drafts()
            self._rows = None if self._rows is None else self._rows[:1]

    def _settle(self, drafts: bool = False) -> None:
        """Evaluate now what :meth:`evaluate` left for later; without ``drafts`` where the cache is to hold the
        context alone (a state about to be kept)."""
        if self._pending:
            self._flush(drafts=drafts)

    def next_logits(self) -> np.ndarray:
        """The logits after the context's last token (a copy)."""
        self._settle(drafts=True)
        if self._rows is None:
            raise ModelError("no logits: nothing was evaluated since the context last changed")
        return self._rows[0].copy()

    def token_bytes(self, token: int) -> bytes:
        return self._piece(token)

    def constrain(self, grammar: Grammar) -> LlamaGrammar:
        return LlamaGrammar(self._lib, self._vocab, self.n_vocab, grammar)

    def first_bytes(self) -> FirstBytes:
        with _MAKING:  # lanes ask at once, from threads of their own: made once
            if self._first_bytes is None:
                self._first_bytes = FirstBytes(self._piece, self.n_vocab)
        return self._first_bytes

    def generate(self, context: Sequence[int], *, grammar: Grammar | None, max_tokens: int, sampling: Sampling,
                 stop: Sequence[str] = (), rng: np.random.Generator | None = None, lines: int = 1) -> Generated:
        """See :meth:`.base.Backend.generate`."""
        return loop.generate(self, context, grammar=grammar, max_tokens=max_tokens, sampling=sampling, stop=stop,
                             rng=rng, lines=lines)
