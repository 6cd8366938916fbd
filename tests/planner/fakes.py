"""A stand-in model for unit tests of prompt assembly and stage plumbing (never the only test of a stage)."""

from __future__ import annotations

import random

from smartllm_local.planner.backends.base import Generated


class FakeBackend:
    """Tokens are 4 characters; each line is drawn from the grammar offered, seeded by the context length."""

    name = "fake"
    model = "fake-model"

    def __init__(self, n_ctx: int = 1_000_000, refuse: bool = False):
        self.n_ctx = n_ctx
        self.refuse = refuse
        self.calls = 0

    def tokenize(self, text: str, *, bos: bool = False) -> list[int]:
        return [0] * (len(text) // 4 + 1 + int(bos))

    def detokenize(self, tokens) -> str:
        return "x" * (4 * len(tokens))

    def generate(self, context, *, grammar, max_tokens, sampling, stop=(), rng=None) -> Generated:
        self.calls += 1
        if grammar is None:
            return Generated([0], "# INFEASIBLE: fake\n" if self.refuse else "", "eos")
        rng = random.Random(len(context))
        for _ in range(200):
            text = grammar.sample(rng)
            if self.refuse == text.startswith("# INFEASIBLE") or text == "":
                break
        return Generated([0] * len(text), text, "line" if text else "eos")

    def close(self) -> None:
        pass
