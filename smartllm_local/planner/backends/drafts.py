"""Drafts from the context itself (prompt lookup): tokens evaluated ahead of the model's choice, kept where it
chooses them.

A plan repeats its prompt: the examples' comments ("# lift it"), call names, object names, the healing token a
forced ``GoToObject`` leaves to the model. So after the last few tokens of the context, the tokens that
followed their latest earlier occurrence are a good guess at what comes next; evaluated in the same batch as the
tokens that must be evaluated anyway, each guess the decoding loop then chooses costs no step of its own. On two
cores a batch of four tokens costs 1.6 times one token (Qwen2.5-Coder-1.5B, 2,000 tokens of context: 128 ms
against 80; three tokens 145 ms: llama.cpp's kernels take rows four at a time), so a batch of fewer than four
tokens is filled up to four; a longer one (a forced line) gets none, since the next choice after forced text takes
a draft less often than the logits of three more rows cost (docs/measurements.md, "Drafts from the context").
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

LONGEST = 4  # the most tokens of the context's end looked up
ROWS = 4  # a batch of fewer tokens is filled with drafts up to this many


def draft_size(pending: int) -> int:
    """How many drafted tokens go into a batch that must evaluate ``pending`` tokens."""
    return max(ROWS - pending, 0)


def lookup(history: Sequence[int], size: int) -> list[int]:
    """Up to ``size`` tokens that followed the latest earlier occurrence of the end of ``history`` (its last
    ``LONGEST`` tokens, else fewer, down to one); none where even its last token has not occurred before."""
    if size <= 0 or len(history) < 2:
        return []
    data = np.asarray(history, dtype=np.int32).tobytes()
    width = np.dtype(np.int32).itemsize
    for n in range(min(LONGEST, len(history) - 1), 0, -1):
        pattern = data[-n * width:]
        end = len(data) - width  # an occurrence that ends before the last token
        while (found := data.rfind(pattern, 0, end)) >= 0:
            if found % width == 0:
                start = found // width + n
                return list(history[start:start + size])
            end = found + len(pattern) - 1
    return []
