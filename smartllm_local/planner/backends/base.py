"""What a backend is: a model that tokenizes and generates, nothing more.

Prompt assembly and grammars live elsewhere; a backend receives the whole
context as tokens (so it can reuse the key/value cache of a shared prefix) and
an optional grammar for the text it may write next.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Protocol

import numpy as np

from ...errors import ModelError
from ..decoding.grammar import Grammar
from ..decoding.sampling import Generated, Sampling


class Backend(Protocol):
    name: str
    model: str  # what was loaded (a path), for the record
    n_ctx: int
    chat_template: str | None  # the model's own chat template (instruct models); None for a base model
    bos_token: str  # the text of the model's control tokens, as chat templates write them ("" if none)
    eos_token: str

    def tokenize(self, text: str, *, bos: bool = False, special: bool = False) -> list[int]:
        """Token ids of ``text``; ``bos`` adds the model's beginning-of-sequence token if it uses one.

        ``special`` reads control-token strings in ``text`` (``<|im_start|>``) as those tokens: for a
        chat template's text, never for a prompt's (there they stay text).
        """

    def detokenize(self, tokens: Sequence[int]) -> str:
        """The text of token ids as a continuation: each token's own bytes, nothing added or dropped."""

    def tokenize_continuation(self, text: str) -> list[int]:
        """Tokens that spell exactly ``text`` written after a context (see :func:`continuation_tokens`)."""

    def prefill(self, context: Sequence[int], prefixes: Sequence[int]) -> int:
        """Evaluate a prompt before generating. ``prefixes`` are where its shared prefixes end, shortest
        first (a stage's examples, the same for every task; then a decomposition's scene, the same for
        every task on the floor plan). The longest prefix with a state kept from an earlier task or
        process starts from that state; each longer one is evaluated on its own and kept, so that reuse
        changes no logit. Returns how many tokens were reused."""

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
        """Continue ``context``.

        With a grammar, generation stops after the token that writes the ``lines``-th newline (its text may run
        on past it, as the grammar admits), or where the model ends the sequence, which is always its choice
        (the text is then a beginning of what the grammar admits). Text the grammar forces is written up to its
        last token, which the model writes (token healing). Without a grammar, it stops at a stop string (which
        is not included), the end of sequence, or ``max_tokens``. ``rng`` draws the samples (temperature > 0).
        """

    def close(self) -> None:
        """Free the model."""


def shared_prefix(cached: Sequence[int], context: Sequence[int]) -> int:
    """How many leading tokens a cache already holds of a new context (list slices compared, halving the
    difference: C speed on prompts of thousands of tokens)."""
    size = min(len(cached), len(context))
    a, b = list(cached[:size]), list(context[:size])
    if a == b:
        return size
    same, differs = 0, size
    while differs - same > 1:
        middle = (same + differs) // 2
        if a[:middle] == b[:middle]:
            same = middle
        else:
            differs = middle
    return same


def keep_whole(alone: Sequence[bool], keep: int) -> int:
    """Where to cut a cache that would keep ``keep`` tokens (``alone``: which were evaluated alone) so that no
    token evaluated in a batch is kept without another of its batch: llama.cpp computes a batch's tokens
    otherwise than a lone one's, and a server can only evaluate such a token again with others (see
    :mod:`slot_mirror`)."""
    if keep >= 1 and not alone[keep - 1] and (keep == 1 or alone[keep - 2]):
        return keep - 1
    return keep


#: What :func:`continuation_tokens` puts before a text, in order: nothing (most tokenizers add nothing of
#: their own), then a newline or a letter, after which a SentencePiece tokenizer adds no space.
_ANCHORS = ("", "\n", "a")


def continuation_tokens(text: str, tokenize: Callable[[str], list[int]], spell: Callable[[int], bytes]) -> list[int]:
    """Tokens that spell exactly ``text`` written after a context, for every tokenizer family.

    So that forced text goes into the context in one batch. A text tokenized on its own is not
    always that: SentencePiece tokenizers (Llama-2's) put a space in front of it. So ``text`` is
    tokenized behind an anchor, and the tokens kept are those after a token boundary where the rest
    spells ``text`` byte for byte (``spell`` gives a token's bytes). Where every anchor merges into
    the text, its two halves are tokenized in turn (a single character parts from some anchor).
    """
    if not text:
        return []
    want = text.encode("utf-8")
    for anchor in _ANCHORS:
        tokens = tokenize(anchor + text)
        start, size = len(tokens), 0
        while start > 0 and size < len(want):
            start -= 1
            size += len(spell(tokens[start]))
        if size == len(want) and b"".join(spell(t) for t in tokens[start:]) == want:
            return tokens[start:]
    if len(text) == 1:
        raise ModelError(f"the model's tokenizer cannot write {text!r}")
    half = len(text) // 2
    return continuation_tokens(text[:half], tokenize, spell) + continuation_tokens(text[half:], tokenize, spell)
