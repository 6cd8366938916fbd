"""The slot mirror against a model of llama-server's cache (longest common prefix kept, a request's new part
one batch, its last token again if all of it is held, each written token alone): at every request for a
line, the slot holds the prompt exactly as the in-process backend's cache would, token by token alone or in
a batch. That the model is the real server's is tested in test_server_backend.py (plans token for token)."""

from __future__ import annotations

import random

from hypothesis import given, settings
from hypothesis import strategies as st

from smartllm_local.planner.backends.base import keep_whole, shared_prefix
from smartllm_local.planner.backends.server.slot_mirror import SlotMirror


class ServerCache:
    """llama-server's slot, as far as how each token it holds was evaluated."""

    def __init__(self):
        self.held: list[int] = []
        self.alone: list[bool] = []
        self.requests = 0

    def request(self, prompt: list[int], written: list[int] = (), ended: bool = False) -> list[int]:
        self.requests += 1
        common = min(shared_prefix(self.held, prompt), len(prompt) - 1)
        self.held = prompt + list(written if ended else written[:-1])
        self.alone = self.alone[:common] + [len(prompt) - common == 1] * (len(prompt) - common)
        self.alone += [True] * (len(self.held) - len(prompt))
        return list(written)


class InProcess:
    """The in-process backend's cache: the spec the mirror follows."""

    def __init__(self):
        self.tokens: list[int] = []
        self.alone: list[bool] = []

    def evaluate(self, tokens: list[int]) -> None:
        self.tokens += tokens
        self.alone += [len(tokens) == 1] * len(tokens)

    def sync(self, context: list[int]) -> None:
        if context == self.tokens:
            return
        common = keep_whole(self.alone, min(shared_prefix(self.tokens, context), len(context) - 1))
        self.tokens, self.alone = self.tokens[:common], self.alone[:common]
        self.evaluate(context[common:])


@settings(max_examples=300, deadline=None)
@given(st.integers(0, 2**32))
def test_at_every_request_for_a_line_the_slot_holds_the_prompt_as_the_in_process_cache_does(seed):
    rng = random.Random(seed)

    def token() -> int:  # few tokens: the server's writing often coincides with forced text
        return rng.randint(1, 4)

    server, local = ServerCache(), InProcess()

    def evaluate(prompt: list[int]) -> None:  # as the backend does: a request, and the mirror told of it
        server.request(prompt)
        mirror.served(prompt)

    mirror = SlotMirror(evaluate)
    examples = [token() for _ in range(rng.randint(2, 12))]
    for _ in range(rng.randint(1, 4)):  # stages and tasks
        context = examples + [token() for _ in range(rng.randint(1, 10))]
        prefixes = [len(examples)] + ([rng.randint(len(examples), len(context) - 1)] if rng.random() < 0.5 else [])
        mirror.prefill(context, prefixes)
        mirror.prepare(context)
        last = max(e for e in prefixes if e < len(context))  # restored from a kept state, then the rest
        local.tokens, local.alone = context[:last], [False] * last
        local.evaluate(context[last:])
        for _ in range(rng.randint(1, 5)):  # lines
            if rng.random() < 0.3:
                context = context[: max(len(examples) + 1, rng.randint(len(context) - 3, len(context)))]  # back
            else:
                context = context + [token() for _ in range(rng.randint(0, 3))]  # text between lines
            mirror.sync(context)
            local.sync(context)
            out: list[int] = []
            for _ in range(rng.randint(1, 6)):
                if rng.random() < 0.4:
                    forced = [token() for _ in range(rng.randint(1, 3))]
                    out += forced
                    mirror.take(forced)
                    local.evaluate(forced)
                    continue
                prompt = context + out
                mirror.prepare(prompt)
                written = [token() for _ in range(rng.randint(1, 5))]
                ended = rng.random() < 0.3
                server.request(prompt, written, ended)
                mirror.served(prompt, written if ended else written[:-1])
                assert server.held[: len(prompt)] == prompt == local.tokens
                assert server.alone[: len(prompt)] == local.alone, (server.alone, local.alone)
                for chosen in written[: rng.randint(1, len(written))]:
                    out.append(chosen)
                    mirror.take([chosen])
                    local.evaluate([chosen])
            context = context + out

