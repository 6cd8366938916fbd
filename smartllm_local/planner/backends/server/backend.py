"""Planning against a model server: llama.cpp's ``llama-server``, llama-cpp-python's server, or vLLM.

The planner stays on this side: prompts, grammars, the line-by-line protocol
and every check. A line is asked for in stretches of the model's own choices,
each request carrying the grammar of what may follow (GBNF), and the planner
writes forced text itself (:mod:`line_requests`); a llama-server slot is kept
as the in-process cache is kept (:mod:`slot_mirror`), so greedy plans are the
in-process backend's. Consecutive requests of a task share all but their last
few tokens, and the server's own prompt cache (llama-server's ``cache_prompt``
with one slot per worker, vLLM's automatic prefix caching, llama-cpp-python's
longest-common-prefix reuse) evaluates only what is new. What a server writes
is checked against the planner's grammar as the in-process backends' output
is: a server that ignores the grammar gives an error, never a plan.

What differs between servers is a :mod:`dialect <dialects>`; the served model's
tokenizer and chat template are read on this side (:mod:`vocabulary`), so
prompt budgets, forced text and the chat template are the in-process backend's.

A server that refuses a connection, answers with an error or says nothing for
``timeout`` seconds fails the request with :class:`ServerError`: the task
fails with that message and a benchmark run goes on.
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from ....errors import ModelError, UserError
from ...decoding.grammar import Grammar
from ...decoding.sampling import END_RANK, Generated, Sampling
from ..base import shared_prefix
from .connection import DEFAULT_TIMEOUT, Connection, ServerError
from .dialects import Dialect, Reply, probe
from .line_requests import LineRequests, WrongLine
from .slot_mirror import SlotMirror
from .vocabulary import RemoteVocabulary, Vocabulary, check_vocabulary, served_vocabulary

__all__ = ["DEFAULT_TIMEOUT", "ServerBackend", "ServerError", "connect"]

#: The likeliest tokens a server that reports them is asked for with each token it writes: as many as the
#: in-process backend looks at before it masks the whole vocabulary, and where the model's end of sequence
#: is its choice.
TOP = END_RANK


class ServerBackend:
    """A model behind an HTTP server, one worker's view of it (its slot, its connection)."""

    name = "server"

    def __init__(self, endpoint: str, vocabulary: Vocabulary, dialect: Dialect, *, n_ctx: int = 8192,
                 slot: int = -1, timeout: float = DEFAULT_TIMEOUT):
        self.connection = Connection(endpoint, timeout)
        self.vocabulary, self.dialect, self.slot = vocabulary, dialect, slot
        self.model = f"{self.connection.url} ({dialect.name}: {vocabulary.model})"
        self.n_ctx = n_ctx
        self.chat_template = vocabulary.chat_template
        self.bos_token, self.eos_token = vocabulary.bos_token, vocabulary.eos_token
        self._bos = vocabulary.bos_added()
        self._texts: dict[int, str] = {}
        # llama-server's slot, kept as the in-process backend keeps its cache (a server that takes text cannot be)
        self._slot = SlotMirror(lambda prompt: self._request(prompt, None, 0, Sampling(), (), 0)) \
            if dialect.mirrors_slots else None

    def tokenize(self, text: str, *, bos: bool = False, special: bool = False) -> list[int]:
        return self.vocabulary.tokenize(text, bos=bos, special=special)

    def detokenize(self, tokens: Sequence[int]) -> str:
        return self.vocabulary.detokenize(tokens)

    def tokenize_continuation(self, text: str) -> list[int]:
        return self.vocabulary.tokenize_continuation(text)

    def prefill(self, context: Sequence[int], prefixes: Sequence[int]) -> int:
        """The prompt is evaluated as the in-process backend evaluates it (:class:`SlotMirror`), the last
        batch with the first request for a line; returns how much of it the slot held. vLLM is asked for one
        token of it, and says how much came from its prefix cache. llama-cpp-python's server says nothing
        of its cache, and evaluates the prompt with the first line."""
        if self._slot is None:
            if not self.dialect.reports_cache:
                return 0
            reply = self._request(list(context), None, 1, Sampling(), (), 0)
            return len(context) - reply.evaluated if reply.evaluated is not None else 0
        held = shared_prefix(self._slot.held, context)
        self._slot.prefill(context, prefixes)
        self._slot.prepare(context)
        return held

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
        """A line is written as the in-process backend writes it (:class:`LineRequests`); free text in one
        request."""
        if len(context) >= self.n_ctx:
            raise ModelError(f"the context ({len(context)} tokens) does not fit n_ctx={self.n_ctx}")
        max_tokens = min(max_tokens, self.n_ctx - len(context) - 1)
        # The server samples with seeds drawn from the stage's generator, whichever worker asks.
        rng = rng or np.random.default_rng(sampling.seed)
        slot = self._slot
        if slot is not None:
            slot.sync(context)

        def ask(prompt: list[int], rest: Grammar, limit: int, banned: Sequence[int] = ()):
            if slot is not None:
                slot.prepare(prompt)
            reply = self._request(prompt, rest.to_gbnf(), limit, sampling, (), int(rng.integers(2**31 - 1)), banned,
                                  TOP if self.dialect.reports_top else 0)
            return self._tokens(reply), reply.probs

        if grammar is None:
            if slot is not None:
                slot.prepare(context)
            reply = self._request(list(context), None, max_tokens, sampling, stop, int(rng.integers(2**31 - 1)))
            return Generated(self._tokens(reply), reply.text, reply.finish)
        try:
            return LineRequests(context, grammar, sampling, ask, self.vocabulary.tokenize_continuation,
                                self._text_of, slot.take if slot is not None else lambda tokens: None,
                                self.vocabulary.end_tokens).write(max_tokens, lines)
        except WrongLine as exc:
            raise ServerError(f"the server at {self.connection.url} wrote {str(exc)!r}, which the line's grammar "
                              "does not allow: it ignores or mis-applies grammars") from exc

    def _request(self, prompt: list[int], grammar: str | None, max_tokens: int, sampling: Sampling,
                 stop: Sequence[str], seed: int, banned: Sequence[int] = (), top: int = 0) -> Reply:
        reply = self._complete(prompt, grammar, max_tokens, sampling, stop, seed, banned, top)
        if self._slot is not None:
            # The server evaluated each token it wrote, alone, before writing the next (the last one too where
            # it went on to end the sequence).
            written = self._tokens(reply)
            self._slot.served(prompt, written if reply.finish == "eos" else written[:-1], reply.evaluated)
        return reply

    def _tokens(self, reply: Reply) -> list[int]:
        """The tokens a server wrote: as it says them, else its text's (a server that takes text tokenizes
        it again anyway)."""
        return reply.tokens if reply.tokens is not None else self.vocabulary.tokenize_continuation(reply.text)

    def _text_of(self, token: int) -> str:
        text = self._texts.get(token)
        if text is None:
            text = self._texts[token] = self.vocabulary.detokenize([token])
        return text

    def _complete(self, context: list[int], grammar: str | None, max_tokens: int, sampling: Sampling,
                  stop: Sequence[str], seed: int, banned: Sequence[int] = (), top: int = 0) -> Reply:
        prompt: list[int] | str = context if self.dialect.takes_tokens else self._text(context)
        path, body = self.dialect.completion(prompt, grammar, max_tokens, sampling.temperature, seed, stop,
                                             self.slot, banned, top)
        started = time.perf_counter()
        status, answer = self.connection.call("POST", path, body)
        if status != 200 or not isinstance(answer, dict):
            message = answer.get("error", answer) if isinstance(answer, dict) else answer
            raise ServerError(f"the server at {self.connection.url} answered {status} to a completion request "
                              f"after {time.perf_counter() - started:.1f} s: {str(message)[:500]}")
        try:
            return self.dialect.reply(answer)
        except (KeyError, IndexError, TypeError) as exc:
            raise ServerError(f"the server at {self.connection.url} answered a completion request with "
                              f"something that is not a completion: {str(answer)[:300]}") from exc

    def _text(self, context: list[int]) -> str:
        """The context as text for a server that tokenizes it (and adds the BOS token itself)."""
        if self._bos is not None and context[:1] == [self._bos]:
            context = context[1:]
        return self.vocabulary.text_of(context)

    def close(self) -> None:
        self.connection.close()


def connect(endpoints: Sequence[str], model: str | None, *, workers: int = 1, n_ctx: int = 8192,
            timeout: float = DEFAULT_TIMEOUT) -> list[ServerBackend]:
    """One backend per worker, spread over the endpoints (and over each llama-server's slots)."""
    found: list[tuple[str, Dialect, int, int]] = []
    vocabulary = None
    for url in endpoints:
        connection = Connection(url, min(timeout, 30.0))
        try:
            dialect, served = probe(connection)
        except ServerError as exc:
            raise UserError(f"--endpoint {url}: {exc}") from exc
        vocabulary = vocabulary or served_vocabulary(model, served, connection, dialect)
        if not (isinstance(vocabulary, RemoteVocabulary) and vocabulary.connection.url == connection.url):
            check_vocabulary(vocabulary, connection, dialect)  # not a server against its own tokenizer
        connection.close()
        # Prompts are fitted within a slot's context and the model's trained one, as in-process.
        limits = [n_ctx, vocabulary.trained_context, served.context]
        context = min(limit for limit in limits if isinstance(limit, int) and limit > 0)
        found.append((url, dialect, served.slots, context))
    assert vocabulary is not None
    backends = []
    for worker in range(workers):
        url, dialect, slots, context = found[worker % len(found)]
        slot = (worker // len(found)) % slots if dialect.mirrors_slots else -1
        backends.append(ServerBackend(url, vocabulary, dialect, n_ctx=context, slot=slot, timeout=timeout))
    return backends
