"""Stand-ins for unit tests of prompt assembly and stage plumbing (never the only test of a stage): a model
and a constraint."""

from __future__ import annotations

import random

from smartllm_local.planner.decoding.grammar import Grammar
from smartllm_local.planner.decoding.protocol import Choose, Constraint, Forced
from smartllm_local.planner.decoding.sampling import Generated


class FakeBackend:
    """Tokens are 4 characters; each line is drawn from the grammar offered, seeded by the context length."""

    name = "fake"
    model = "fake-model"
    chat_template = None  # a base model: prompts go in raw
    bos_token = eos_token = ""

    def __init__(self, n_ctx: int = 1_000_000, refuse: bool = False):
        self.n_ctx = n_ctx
        self.refuse = refuse
        self.calls = 0

    def tokenize(self, text: str, *, bos: bool = False, special: bool = False) -> list[int]:
        return [0] * (len(text) // 4 + 1 + int(bos))

    def detokenize(self, tokens) -> str:
        return "x" * (4 * len(tokens))

    def tokenize_continuation(self, text: str) -> list[int]:
        """Forced text costs a token a character, the most it can with a real tokenizer."""
        return [0] * len(text)

    def prefill(self, context, shared: int) -> int:
        return 0

    def generate(self, context, *, grammar, max_tokens, sampling, stop=(), rng=None, lines=1) -> Generated:
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


class Script(Constraint):
    """A constraint that writes its forced texts and offers its grammars, in order."""

    def __init__(self, *steps: str | Grammar):
        super().__init__()
        self._steps = list(steps)

    def next(self, remaining: int) -> Forced | Choose | None:
        if not self._steps:
            return None
        step = self._steps.pop(0)
        if isinstance(step, str):
            return Forced(step)
        self._offered = Choose(step, {"line": step})
        return self._offered

    def _advance(self, kind: str, piece: str) -> None:
        pass

    def minimum_budget(self) -> int:
        return 0
