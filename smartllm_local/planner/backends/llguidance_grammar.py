"""llguidance's grammar as the decoding loop's token mask (:class:`..decoding.loop.TokenConstraint`): the transformers
backend's grammar engine, the one outlines uses, called directly so that there is no silent unconstrained fallback."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..decoding.grammar import Grammar, GrammarError


class LLGuidanceGrammar:
    """A GBNF grammar compiled by llguidance for a tokenizer; its mask of the whole vocabulary is computed once a
    step, when the loop first asks about a token."""

    name = "llguidance"

    def __init__(self, llg: Any, tokenizer: Any, n_vocab: int, grammar: Grammar):
        import llguidance.torch

        self._fill = llguidance.torch.fill_next_token_bitmask
        self._n_vocab = n_vocab
        self._matcher = llg.LLMatcher(tokenizer, llg.grammar_from("gbnf", grammar.to_gbnf()))
        if self._matcher.is_error():
            raise GrammarError(f"llguidance rejected a grammar: {self._matcher.get_error()}")
        self._bits = llguidance.torch.allocate_token_bitmask(1, n_vocab)  # on the CPU: llguidance fills it there
        self._allowed: np.ndarray | None = None

    def _mask(self) -> np.ndarray:
        if self._allowed is None:
            # llguidance's own apply function goes through torch.compile (seconds per call): unpacked here.
            self._fill(self._matcher, self._bits, 0)
            bits = np.unpackbits(self._bits.numpy().view(np.uint8), bitorder="little")[: self._n_vocab]
            self._allowed = bits.astype(bool)
        return self._allowed

    def admits(self, token: int) -> bool:
        return bool(self._mask()[token])

    def mask(self, logits: np.ndarray, ids: np.ndarray | None = None) -> np.ndarray:
        allowed = self._mask() if ids is None else self._mask()[ids]
        return np.where(allowed, logits, -np.inf).astype(np.float32)

    def accept(self, token: int) -> bool:
        self._allowed = None
        return bool(self._matcher.consume_token(token))

    def close(self) -> None:
        """Nothing to free: llguidance's matcher goes with its last reference."""
