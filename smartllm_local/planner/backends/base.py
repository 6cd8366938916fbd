"""What a backend is: a model that tokenizes and generates, nothing more.

Prompt assembly and grammars live elsewhere; a backend receives the whole
context as tokens (so it can reuse the key/value cache of a shared prefix) and
an optional grammar for the text it may write next.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, Sequence

from ..grammar import Grammar


@dataclass(frozen=True)
class Sampling:
    """Decoding settings; temperature 0 is greedy, the seed makes sampling reproducible."""

    temperature: float = 0.0
    seed: int = 0


@dataclass
class Generated:
    tokens: list[int]
    text: str
    stop: str  # "line" (a grammar line completed), "eos", "stop" (a stop string), "length"


class Backend(Protocol):
    name: str
    model: str  # what was loaded (a path), for the record
    n_ctx: int

    def tokenize(self, text: str, *, bos: bool = False) -> list[int]:
        """Token ids of ``text``; ``bos`` adds the model's beginning-of-sequence token if it uses one."""

    def detokenize(self, tokens: Sequence[int]) -> str:
        """The text of token ids."""

    def generate(
        self,
        context: Sequence[int],
        *,
        grammar: Grammar | None,
        max_tokens: int,
        sampling: Sampling,
        stop: Sequence[str] = (),
    ) -> Generated:
        """Continue ``context``.

        With a grammar (every line grammar admits one line ending in a newline,
        or the empty string), generation stops as soon as a line is complete or
        the model ends the sequence. Without one, it stops at a stop string
        (which is not included), the end of sequence, or ``max_tokens``.
        """

    def close(self) -> None:
        """Free the model."""


def shared_prefix(cached: Sequence[int], context: Sequence[int]) -> int:
    """How many leading tokens a cache already holds of a new context."""
    common = 0
    for a, b in zip(cached, context):
        if a != b:
            break
        common += 1
    return common
