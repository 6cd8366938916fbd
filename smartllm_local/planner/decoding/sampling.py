"""What a backend is asked for and gives back, below every backend and the decoding loop that drives them:
the sampling settings, what a call generated, and where the model may end the sequence."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from .repetition import LoopGuard


@dataclass(frozen=True)
class Sampling:
    """Decoding settings; temperature 0 is greedy, the seed makes sampling reproducible, and
    ``loop_guard`` (None: off) keeps a line from ending in text said three times over (and, where a stage is
    written line by line, a block of lines from being begun a third time). ``aligned``: forced
    text ends with the model's own token, line ends are open and the end of sequence is always the model's
    choice (off, for measuring its effect: forced text is written whole, a line ends at its newline, and
    the model may end only where the grammar may)."""

    temperature: float = 0.0
    seed: int = 0
    loop_guard: LoopGuard | None = LoopGuard()
    aligned: bool = True


@dataclass
class Generated:
    tokens: list[int]
    text: str
    stop: str  # "line" (a grammar line completed), "eos", "stop" (a stop string), "length"
    loops: int = 0  # loops the loop guard ended
    forced: int = 0  # of ``tokens``, those the backend wrote itself (text the grammar forces), not the model
    choices: int = 0  # tokens the model chose (the end of sequence included)
    refused: int = 0  # of those, the ones where its likeliest token was one the grammar refused
    logprob: float = 0.0  # the sum of the chosen tokens' log-probabilities under the model, unconstrained


#: The end of sequence is the model's choice where it is among its ``END_RANK`` likeliest next tokens (and, greedy,
#: likelier than every token the grammar admits): there the model means to stop. Further down it is only the least
#: unlikely of what the grammar leaves, and the model goes on under the grammar instead. A server reports as many of
#: its likeliest tokens (llama-server's ``n_probs``), so that it decides the same.
END_RANK = 64


def may_end(logits: Any, token: int) -> bool:
    """Whether the end-of-sequence ``token`` is among the model's ``END_RANK`` likeliest (numpy or torch scores)."""
    return int((logits > logits[token]).sum()) < END_RANK
