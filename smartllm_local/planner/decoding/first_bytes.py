"""The vocabulary by first byte: which tokens can come next where a grammar admits only some characters.

A token the grammar admits begins with a character the grammar admits next, so a whole-vocabulary mask need only
ask the grammar engine about the tokens that begin with one of those characters' first bytes, and every other
token is refused without asking. llama.cpp's grammar sampler costs about its candidates' count: over Llama-2's
32,000 tokens some 2 ms a step on two cores, spent wherever the model's likeliest tokens are all refused (a
random-weight model's, at every step; sampling, where the draw is refused).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

import numpy as np

_NONE = 256  # the bucket of tokens with no bytes (control tokens): always asked about


class FirstBytes:
    """A model's token ids grouped by their first byte (made once per model: a call per token)."""

    def __init__(self, spell: Callable[[int], bytes], n_vocab: int):
        first = np.full(n_vocab, _NONE, dtype=np.int16)
        for token in range(n_vocab):
            piece = spell(token)
            if piece:
                first[token] = piece[0]
        order = np.argsort(first, kind="stable").astype(np.int32)
        bounds = np.searchsorted(first[order], np.arange(_NONE + 2))
        self._by_byte = [order[bounds[b]:bounds[b + 1]] for b in range(_NONE + 1)]

    def starting_with(self, chars: Iterable[str]) -> np.ndarray:
        """The ids of the tokens whose text can begin with one of ``chars`` (and of those with no text)."""
        firsts = {c.encode("utf-8")[0] for c in chars} | {_NONE}
        return np.concatenate([self._by_byte[b] for b in firsts])
