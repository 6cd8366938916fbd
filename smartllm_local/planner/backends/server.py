"""Planning against a model server: llama.cpp's ``llama-server`` or llama-cpp-python's server.

The planner stays on this side: prompts, grammars, the line-by-line protocol
and every check. A line is asked for in stretches of the model's own choices,
each request carrying the grammar of what may follow (GBNF), and the planner
writes forced text itself (:mod:`line_requests`); a llama-server slot is kept
as the in-process cache is kept (:mod:`slot_mirror`), so greedy plans are the
in-process backend's. Consecutive requests of a task share all but their last
few tokens, and the server's own prompt cache (llama-server's ``cache_prompt``
with one slot per worker, llama-cpp-python's longest-common-prefix reuse)
evaluates only what is new. What a server writes is checked against the
planner's grammar as the in-process backends' output is: a server that ignores
the grammar gives an error, never a plan.

The vocabulary is the served model's: read here from the GGUF file
(``vocab_only``: its metadata, not its weights) where there is one, or asked
of llama-server (``/tokenize``, ``/props``) where the file is on another
machine; so prompt budgets, forced text and the chat template are the
in-process backend's. llama-server takes the context as token ids and
returns the ids it wrote; llama-cpp-python's server takes text only, which it
tokenizes again (see the README for what that changes).

A server that refuses a connection, answers with an error or says nothing for
``timeout`` seconds fails the request with :class:`ServerError`: the task
fails with that message and a benchmark run goes on.
"""

from __future__ import annotations

import functools
import http.client
import json
import socket
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol, Sequence
from urllib.parse import urlsplit

import numpy as np

from ...errors import ModelError, SmartLLMError, UserError
from ..grammar import Grammar
from .base import Generated, Sampling, continuation_tokens, shared_prefix
from .line_requests import LineRequests, WrongLine
from .llamacpp import LlamaCppBackend
from .slot_mirror import SlotMirror

#: How long a request may go without an answer before the task fails (a 70B model evaluating a
#: 3,000-token prompt on a GPU takes seconds; on CPUs, minutes).
DEFAULT_TIMEOUT = 300.0


class ServerError(SmartLLMError):
    """A model server failed a request: unreachable, an error status, or no answer in time."""


@dataclass(frozen=True)
class Reply:
    text: str
    tokens: list[int] | None  # the ids written, where the server says them
    finish: str  # "eos", "length" or "stop"
    evaluated: int | None = None  # prompt tokens the server evaluated (not taken from its cache), if it says


class Connection:
    """One kept-alive HTTP connection to one server, with a bound on every wait."""

    def __init__(self, url: str, timeout: float):
        parts = urlsplit(url if "://" in url else f"http://{url}")
        if parts.scheme not in ("http", "https") or not parts.hostname:
            raise UserError(f"--endpoint {url!r} is not an http(s) URL such as http://127.0.0.1:8080")
        self.url, self.timeout = f"{parts.scheme}://{parts.netloc}", timeout
        self._host, self._port, self._https = parts.hostname, parts.port, parts.scheme == "https"
        self._base = parts.path.rstrip("/")
        self._conn: http.client.HTTPConnection | None = None
        self._closed = False  # by close(): no request is sent again
        self._lock = threading.Lock()

    def call(self, method: str, path: str, body: dict[str, Any] | None = None) -> tuple[int, Any]:
        """The status and the decoded JSON answer; a dropped kept-alive connection is opened again once."""
        for attempt in (0, 1):
            try:
                conn = self._conn or self._open()
                conn.request(method, self._base + path, body=None if body is None else json.dumps(body),
                             headers={"Content-Type": "application/json"})
                answer = conn.getresponse()
                raw = answer.read()
                break
            except (socket.timeout, TimeoutError) as exc:
                self._drop()
                raise ServerError(f"the server at {self.url} gave no answer in {self.timeout:g} s "
                                  "(stalled or overloaded); raise --server-timeout for a slow model") from exc
            except (ConnectionError, http.client.HTTPException, OSError) as exc:
                self._drop()
                if attempt == 0 and isinstance(exc, (http.client.RemoteDisconnected, BrokenPipeError,
                                                     ConnectionResetError)):
                    continue  # the server closed an idle kept-alive connection
                raise ServerError(f"the server at {self.url} cannot be reached ({exc}); is it running?") from exc
        try:
            return answer.status, json.loads(raw) if raw else None
        except ValueError:
            return answer.status, raw.decode("utf-8", errors="replace")

    def _open(self) -> http.client.HTTPConnection:
        kind = http.client.HTTPSConnection if self._https else http.client.HTTPConnection
        conn = kind(self._host, self._port, timeout=self.timeout)
        conn.connect()  # its socket exists before close() can see it
        with self._lock:
            if not self._closed:
                self._conn = conn
                return conn
        conn.close()
        raise ServerError(f"the connection to the server at {self.url} was closed (the run is ending)")

    def close(self) -> None:
        """Close the connection for good; a request waiting on it in another thread (a worker, when Ctrl-C
        ends a run) fails at once rather than at the timeout, and is not sent again."""
        with self._lock:
            self._closed = True
        self._drop()

    def _drop(self) -> None:
        with self._lock:
            conn, self._conn = self._conn, None
        if conn is not None:
            if conn.sock is not None:
                try:
                    conn.sock.shutdown(socket.SHUT_RDWR)  # wakes a thread waiting on it
                except OSError:
                    pass
            conn.close()


class Dialect(Protocol):
    """What differs between servers: how a line is asked for, and what the answer says."""

    name: str
    #: Whether the server takes the context as token ids (else as text, tokenized again there).
    takes_tokens: bool

    def completion(self, prompt: list[int] | str, grammar: str | None, max_tokens: int, temperature: float,
                   seed: int, stop: Sequence[str], slot: int, banned: Sequence[int]) -> tuple[str, dict[str, Any]]:
        """The path and body of a completion request (``banned``: tokens it must not write)."""

    def reply(self, answer: dict[str, Any]) -> Reply:
        """What a completion's answer says."""


# Sampling the planner's way: greedy at temperature 0, else the model's whole distribution (no top-k, top-p,
# min-p or penalties, which servers otherwise apply by default).
_PLAIN = {"top_k": 0, "top_p": 1.0, "min_p": 0.0, "repeat_penalty": 1.0, "presence_penalty": 0.0,
          "frequency_penalty": 0.0}


class LlamaServer:
    """llama.cpp's ``llama-server``: token ids in and out, one slot per worker, its prompt cache on."""

    name = "llama-server"
    takes_tokens = True

    def completion(self, prompt, grammar, max_tokens, temperature, seed, stop, slot, banned):
        body = {"prompt": prompt, "n_predict": max_tokens, "temperature": temperature, "seed": seed,
                "stop": list(stop), "cache_prompt": True, "id_slot": slot, "return_tokens": True,
                "logit_bias": [[t, False] for t in banned], **_PLAIN}
        if grammar is not None:
            body["grammar"] = grammar
        return "/completion", body

    def reply(self, answer):
        finish = {"eos": "eos", "limit": "length", "word": "stop"}.get(answer.get("stop_type", ""), "length")
        evaluated = (answer.get("timings") or {}).get("prompt_n")
        return Reply(answer["content"], list(answer.get("tokens") or []), finish, evaluated)


class LlamaCppPythonServer:
    """llama-cpp-python's ``python -m llama_cpp.server``: OpenAI completions with a ``grammar`` field, text in
    and out."""

    name = "llama-cpp-python"
    takes_tokens = False

    def completion(self, prompt, grammar, max_tokens, temperature, seed, stop, slot, banned):
        body = {"prompt": prompt, "max_tokens": max_tokens, "temperature": temperature, "seed": seed,
                "stop": list(stop), "logit_bias": {str(t): -1e30 for t in banned}, **_PLAIN}
        if grammar is not None:
            body["grammar"] = grammar
        return "/v1/completions", body

    def reply(self, answer):
        choice = answer["choices"][0]
        finish = choice.get("finish_reason") or "length"
        return Reply(choice["text"], None, "length" if finish == "length" else "stop")


def probe(connection: Connection) -> tuple[Dialect, dict[str, Any]]:
    """Which server answers at an endpoint, and what it says about itself (llama-server's ``/props``)."""
    status, props = connection.call("GET", "/props")
    if status == 200 and isinstance(props, dict) and "default_generation_settings" in props:
        return LlamaServer(), props
    status, models = connection.call("GET", "/v1/models")
    if status == 200 and isinstance(models, dict) and models.get("data"):
        return LlamaCppPythonServer(), {"model_path": models["data"][0].get("id", "")}
    raise UserError(f"{connection.url} answers, but neither as llama-server (GET /props) nor as an OpenAI-compatible "
                    "server (GET /v1/models); start llama-server or python -m llama_cpp.server there")


class Vocabulary(Protocol):
    """The served model's tokenizer and chat template."""

    model: str
    chat_template: str | None
    bos_token: str
    eos_token: str
    trained_context: int | None  # the context the model was trained on, where the vocabulary says

    def tokenize(self, text: str, *, bos: bool = False, special: bool = False) -> list[int]: ...
    def detokenize(self, tokens: Sequence[int]) -> str: ...
    def tokenize_continuation(self, text: str) -> list[int]: ...
    def text_of(self, tokens: Sequence[int]) -> str: ...
    def bos_added(self) -> int | None:
        """The token the tokenizer puts in front of a prompt, if it does."""


class LocalVocabulary:
    """The vocabulary of a GGUF file on this machine (llama.cpp, ``vocab_only``)."""

    def __init__(self, path: Path):
        self._llama = LlamaCppBackend(path, n_ctx=512, vocab_only=True)
        self.model, self.chat_template = self._llama.model, self._llama.chat_template
        self.bos_token, self.eos_token = self._llama.bos_token, self._llama.eos_token
        self.trained_context = self._llama.trained_context
        self.tokenize, self.detokenize = self._llama.tokenize, self._llama.detokenize
        self.tokenize_continuation, self.text_of = self._llama.tokenize_continuation, self._llama.text_of

    def bos_added(self) -> int | None:
        return self._llama.llm.token_bos() if self._llama.adds_bos() else None


class RemoteVocabulary:
    """llama-server's own tokenizer (``/tokenize`` with each token's piece) and chat template (``/props``),
    for a model whose file is on the server's machine only. A token is spelled by its piece as the
    server writes it; the few that are part of a character come back as their bytes."""

    def __init__(self, connection: Connection, props: dict[str, Any]):
        self.connection = connection
        self.model = str(props.get("model_path") or connection.url)
        self.chat_template = props.get("chat_template") or None
        self.bos_token, self.eos_token = str(props.get("bos_token") or ""), str(props.get("eos_token") or "")
        self.trained_context = None  # llama-server says its slots' context instead
        self._pieces: dict[int, bytes] = {}
        self._lock = threading.Lock()  # the workers share it, and its one connection

    def _call(self, path: str, body: dict[str, Any]) -> Any:
        with self._lock:
            status, answer = self.connection.call("POST", path, body)
        if status != 200 or not isinstance(answer, dict):
            raise ServerError(f"the server at {self.connection.url} answered {status} to {path}: {str(answer)[:300]}")
        return answer

    def tokenize(self, text: str, *, bos: bool = False, special: bool = False) -> list[int]:
        answer = self._call("/tokenize", {"content": text, "add_special": bos, "parse_special": special,
                                          "with_pieces": True})
        tokens = []
        for entry in answer["tokens"]:
            piece = entry["piece"]
            self._pieces.setdefault(entry["id"], piece.encode("utf-8") if isinstance(piece, str) else bytes(piece))
            tokens.append(entry["id"])
        return tokens

    def _piece(self, token: int) -> bytes:
        if token not in self._pieces:
            self._pieces[token] = self._call("/detokenize", {"tokens": [token]})["content"].encode("utf-8")
        return self._pieces[token]

    def detokenize(self, tokens: Sequence[int]) -> str:
        return b"".join(self._piece(t) for t in tokens).decode("utf-8", errors="replace")

    def tokenize_continuation(self, text: str) -> list[int]:
        return continuation_tokens(text, self.tokenize, self._piece)

    def text_of(self, tokens: Sequence[int]) -> str:
        return self.detokenize(tokens)

    @functools.cached_property
    def _bos(self) -> int | None:
        with_bos, without = self.tokenize("a", bos=True), self.tokenize("a")
        return with_bos[0] if len(with_bos) > len(without) else None

    def bos_added(self) -> int | None:
        return self._bos  # asked once per worker: the server is asked once


def served_vocabulary(model: str | None, props: dict[str, Any], connection: Connection,
                      dialect: Dialect) -> Vocabulary:
    """The served model's vocabulary: from ``--model``, else from the file the server names where it is
    on this machine, else from llama-server itself."""
    from ..models import resolve_gguf

    served = props.get("model_path") or None
    if model is not None:
        return LocalVocabulary(resolve_gguf(model))
    if served is not None and Path(served).is_file():
        return LocalVocabulary(resolve_gguf(served))
    if dialect.takes_tokens:
        return RemoteVocabulary(Connection(connection.url, connection.timeout), props)
    raise UserError(f"the vocabulary of the model served at {connection.url} cannot be read here: pass --model with a "
                    "copy of the served GGUF file (only its vocabulary and chat template are read, not its weights)")


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
            if dialect.takes_tokens else None

    def tokenize(self, text: str, *, bos: bool = False, special: bool = False) -> list[int]:
        return self.vocabulary.tokenize(text, bos=bos, special=special)

    def detokenize(self, tokens: Sequence[int]) -> str:
        return self.vocabulary.detokenize(tokens)

    def tokenize_continuation(self, text: str) -> list[int]:
        return self.vocabulary.tokenize_continuation(text)

    def prefill(self, context: Sequence[int], prefixes: Sequence[int]) -> int:
        """The prompt is evaluated as the in-process backend evaluates it (:class:`SlotMirror`), the last
        batch with the first request for a line; returns how much of it the slot held. llama-cpp-python's
        server cannot be steered so, and evaluates it with the first line."""
        if self._slot is None:
            return 0
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

        def ask(prompt: list[int], rest: Grammar | None, limit: int, banned: Sequence[int] = ()) -> list[int]:
            if slot is not None:
                slot.prepare(prompt)
            return self._tokens(self._request(prompt, None if rest is None else rest.to_gbnf(), limit, sampling,
                                              stop if rest is None else (), int(rng.integers(2**31 - 1)), banned))

        if grammar is None:
            if slot is not None:
                slot.prepare(context)
            reply = self._request(list(context), None, max_tokens, sampling, stop, int(rng.integers(2**31 - 1)))
            return Generated(self._tokens(reply), reply.text, reply.finish)
        try:
            return LineRequests(context, grammar, sampling, ask, self.vocabulary.tokenize_continuation,
                                self._text_of, slot.take if slot is not None else lambda tokens: None).write(max_tokens)
        except WrongLine as exc:
            raise ServerError(f"the server at {self.connection.url} wrote {str(exc)!r}, which the line's grammar "
                              "does not allow: it ignores or mis-applies grammars") from exc

    def _request(self, prompt: list[int], grammar: str | None, max_tokens: int, sampling: Sampling,
                 stop: Sequence[str], seed: int, banned: Sequence[int] = ()) -> Reply:
        reply = self._complete(prompt, grammar, max_tokens, sampling, stop, seed, banned)
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
                  stop: Sequence[str], seed: int, banned: Sequence[int] = ()) -> Reply:
        prompt: list[int] | str = context if self.dialect.takes_tokens else self._text(context)
        path, body = self.dialect.completion(prompt, grammar, max_tokens, sampling.temperature, seed, stop,
                                             self.slot, banned)
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


def check_vocabulary(vocabulary: Vocabulary, connection: Connection, dialect: Dialect) -> None:
    """Refuse a ``--model`` whose tokenizer is not the served model's: its budgets and tokens would be wrong."""
    probe_text = "Robots: GoToObject(robots[0], 'Fridge') # 3 steps\n"
    path = "/tokenize" if dialect.takes_tokens else "/extras/tokenize"
    body = {"content": probe_text, "add_special": False} if dialect.takes_tokens else {"input": probe_text}
    status, answer = connection.call("POST", path, body)
    if status != 200 or not isinstance(answer, dict) or "tokens" not in answer:
        return  # a server without a tokenizer endpoint: nothing to compare with
    theirs = [t if isinstance(t, int) else t.get("id") for t in answer["tokens"]]
    ours = vocabulary.tokenize(probe_text)
    if theirs[-len(ours):] != ours:  # llama-cpp-python's endpoint puts BOS in front
        raise UserError(f"the server at {connection.url} tokenizes text differently from {vocabulary.model}: "
                        "pass --model with the GGUF file the server serves")


def connect(endpoints: Sequence[str], model: str | None, *, workers: int = 1, n_ctx: int = 8192,
            timeout: float = DEFAULT_TIMEOUT) -> list[ServerBackend]:
    """One backend per worker, spread over the endpoints (and over each llama-server's slots)."""
    found: list[tuple[str, Dialect, int, int]] = []
    vocabulary = None
    for url in endpoints:
        connection = Connection(url, min(timeout, 30.0))
        try:
            dialect, props = probe(connection)
        except ServerError as exc:
            raise UserError(f"--endpoint {url}: {exc}") from exc
        vocabulary = vocabulary or served_vocabulary(model, props, connection, dialect)
        if not (isinstance(vocabulary, RemoteVocabulary) and vocabulary.connection.url == connection.url):
            check_vocabulary(vocabulary, connection, dialect)  # not a server against its own tokenizer
        connection.close()
        # Prompts are fitted within a slot's context and the model's trained one, as in-process.
        slot_ctx = (props.get("default_generation_settings") or {}).get("n_ctx")
        limits = [n_ctx, vocabulary.trained_context, slot_ctx]
        context = min(limit for limit in limits if isinstance(limit, int) and limit > 0)
        found.append((url, dialect, int(props.get("total_slots") or 1), context))
    assert vocabulary is not None
    backends = []
    for worker in range(workers):
        url, dialect, slots, context = found[worker % len(found)]
        slot = (worker // len(found)) % slots if dialect.takes_tokens else -1
        backends.append(ServerBackend(url, vocabulary, dialect, n_ctx=context, slot=slot, timeout=timeout))
    return backends
