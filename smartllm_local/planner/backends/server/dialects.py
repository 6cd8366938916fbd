"""What differs between model servers: how one is recognized, how a completion is asked of it, and what
its answer says.

Each server is a dialect behind one small protocol, tried in turn on an endpoint (:func:`probe`); the
planner's side (line requests, checks, the vocabulary) is the same for all. A server that takes no
grammar with its requests is not recognized rather than trusted: its plans would not be constrained.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

from ....errors import UserError
from .connection import Connection

#: A written token's log-probability under the unconstrained model, and the likeliest tokens there, with theirs.
TokenProbs = tuple[float, list[tuple[int, float]]]


@dataclass(frozen=True)
class Reply:
    text: str
    tokens: list[int] | None  # the ids written, where the server says them
    finish: str  # "eos", "length" or "stop"
    evaluated: int | None = None  # prompt tokens the server evaluated (not taken from its cache), if it says
    probs: list[TokenProbs] | None = None  # per token written, where the server was asked for them


@dataclass(frozen=True)
class Served:
    """What a server says about itself."""

    model: str | None  # the served model's path (or name), where it says
    context: int | None = None  # tokens one request may hold: a llama-server slot's context, vLLM's max_model_len
    slots: int = 1  # llama-server's -np: contexts kept apart, one worker each
    props: dict[str, Any] = field(default_factory=dict)  # llama-server's /props, for its vocabulary


class Unsupported(Exception):
    """The server is a dialect's, but one the planner cannot plan against (the message says why and what to do)."""


#: GET a path of the server once: its decoded answer, or None where it does not answer 200.
Get = Callable[[str], Any]


class Dialect(Protocol):
    """One server's way of taking a line's request."""

    name: str
    #: The context goes as token ids (else as text, which the server tokenizes again).
    takes_tokens: bool
    #: A slot can be kept as the in-process cache is kept (:mod:`slot_mirror`): llama-server only.
    mirrors_slots: bool
    #: Its tokenizer and chat template can be read over HTTP (:class:`RemoteVocabulary`).
    serves_vocabulary: bool
    #: Its answers say how much of the prompt came from its cache, so a prompt's reuse can be recorded.
    reports_cache: bool
    #: It says, for each token it writes, the likeliest tokens of the unconstrained model (before the grammar):
    #: the model's end of sequence is then its choice, and how far the grammar bent it is measured.
    reports_top: bool

    def recognize(self, get: Get) -> Served | None:
        """What the server at the other end says about itself, if it is this dialect's (:class:`Unsupported`
        where it is, but cannot be planned against)."""

    def completion(self, prompt: list[int] | str, grammar: str | None, max_tokens: int, temperature: float,
                   seed: int, stop: Sequence[str], slot: int, banned: Sequence[int],
                   top: int = 0) -> tuple[str, dict[str, Any]]:
        """The path and body of a completion request (``banned``: tokens it must not write; ``top``: how many of
        the likeliest tokens to report for each token written, where it reports them)."""

    def reply(self, answer: dict[str, Any]) -> Reply:
        """What a completion's answer says."""

    def tokenize(self, text: str) -> tuple[str, dict[str, Any]]:
        """The path and body of a request for the tokens of ``text`` (answered ``{"tokens": [...]}``)."""


# Sampling the planner's way: greedy at temperature 0, else the model's whole distribution (no top-k, top-p,
# min-p or penalties, which servers otherwise apply by default).
_PLAIN = {"top_k": 0, "top_p": 1.0, "min_p": 0.0, "presence_penalty": 0.0, "frequency_penalty": 0.0}


def _first_model(get: Get) -> dict[str, Any] | None:
    """The first model an OpenAI-compatible server lists."""
    models = get("/v1/models")
    data = models.get("data") if isinstance(models, dict) else None
    return data[0] if isinstance(data, list) and data and isinstance(data[0], dict) else None


class LlamaServer:
    """llama.cpp's ``llama-server``: token ids in and out, one slot per worker, its prompt cache on."""

    name = "llama-server"
    takes_tokens = mirrors_slots = serves_vocabulary = reports_cache = reports_top = True

    def recognize(self, get):
        props = get("/props")
        if not (isinstance(props, dict) and "default_generation_settings" in props):
            return None
        return Served(props.get("model_path") or None, props["default_generation_settings"].get("n_ctx"),
                      int(props.get("total_slots") or 1), props)

    def completion(self, prompt, grammar, max_tokens, temperature, seed, stop, slot, banned, top=0):
        body = {"prompt": prompt, "n_predict": max_tokens, "temperature": temperature, "seed": seed,
                "stop": list(stop), "cache_prompt": True, "id_slot": slot, "return_tokens": True,
                "logit_bias": [[t, False] for t in banned], "repeat_penalty": 1.0, **_PLAIN}
        if grammar is not None:
            body["grammar"] = grammar
        if top:  # from the logits before any sampler, the grammar's included (post_sampling_probs off)
            body.update(n_probs=top, post_sampling_probs=False)
        return "/completion", body

    def reply(self, answer):
        finish = {"eos": "eos", "limit": "length", "word": "stop"}.get(answer.get("stop_type", ""), "length")
        evaluated = (answer.get("timings") or {}).get("prompt_n")
        probs = None
        if "completion_probabilities" in answer:
            probs = [(float(p["logprob"]), [(int(t["id"]), float(t["logprob"])) for t in p["top_logprobs"]])
                     for p in answer["completion_probabilities"]]
        return Reply(answer["content"], list(answer.get("tokens") or []), finish, evaluated, probs)

    def tokenize(self, text):
        return "/tokenize", {"content": text, "add_special": False}


class Vllm:
    """vLLM's OpenAI-compatible server (``vllm serve``): token ids in and out (``return_token_ids``), the grammar
    as ``structured_outputs.grammar`` (GBNF, compiled by XGrammar or llguidance), its automatic prefix cache
    shared by every worker (continuous batching: no slots)."""

    name = "vLLM"
    takes_tokens = reports_cache = True
    mirrors_slots = serves_vocabulary = reports_top = False

    def recognize(self, get):
        model = _first_model(get)
        if model is None or model.get("owned_by") != "vllm":
            return None
        answer = get("/version")
        version = str(answer.get("version", "")) if isinstance(answer, dict) else ""
        found = re.match(r"(\d+)\.(\d+)", version)
        if found and (int(found[1]), int(found[2])) < (0, 12):
            # older ones read the grammar from guided_grammar, and ignore a field they do not know
            raise Unsupported(f"version {version} takes grammars in a field the planner does not send "
                              "(structured_outputs came with 0.12): upgrade vLLM there")
        return Served(model.get("root") or model.get("id"), model.get("max_model_len"))

    def completion(self, prompt, grammar, max_tokens, temperature, seed, stop, slot, banned, top=0):
        body = {"prompt": prompt, "max_tokens": max_tokens, "temperature": temperature, "seed": seed,
                "stop": list(stop), "return_token_ids": True, "repetition_penalty": 1.0,
                "logit_bias": {str(t): -100.0 for t in banned}, **_PLAIN}  # -100: OpenAI's floor, which vLLM keeps
        if grammar is not None:
            body["structured_outputs"] = {"grammar": grammar}
        return "/v1/completions", body

    def reply(self, answer):
        choice = answer["choices"][0]
        tokens = choice.get("token_ids")
        finish, why = choice.get("finish_reason"), choice.get("stop_reason")
        if finish == "stop" and isinstance(why, str):
            end, tokens = "stop", None  # the text is cut before the stop string, the ids are not: spell the text
        elif finish == "stop":
            end = "eos"  # the end of the sequence (or a stop token, its id in stop_reason), last of the ids
            tokens = tokens[:-1] if tokens else tokens
        else:
            end = "length"
        usage = answer.get("usage") or {}
        cached = (usage.get("prompt_tokens_details") or {}).get("cached_tokens")  # --enable-prompt-tokens-details
        evaluated = usage["prompt_tokens"] - cached if isinstance(cached, int) and "prompt_tokens" in usage else None
        return Reply(choice["text"], None if tokens is None else list(tokens), end, evaluated)

    def tokenize(self, text):
        return "/tokenize", {"prompt": text, "add_special_tokens": False}


class LlamaCppPythonServer:
    """llama-cpp-python's ``python -m llama_cpp.server``: OpenAI completions with a ``grammar`` field, text in
    and out."""

    name = "llama-cpp-python"
    takes_tokens = mirrors_slots = serves_vocabulary = reports_cache = reports_top = False

    def recognize(self, get):
        model = _first_model(get)
        if model is None or model.get("owned_by") != "me":  # what llama_cpp.server says of every model
            return None
        return Served(model.get("id"))

    def completion(self, prompt, grammar, max_tokens, temperature, seed, stop, slot, banned, top=0):
        body = {"prompt": prompt, "max_tokens": max_tokens, "temperature": temperature, "seed": seed,
                "stop": list(stop), "logit_bias": {str(t): -1e30 for t in banned}, "repeat_penalty": 1.0, **_PLAIN}
        if grammar is not None:
            body["grammar"] = grammar
        return "/v1/completions", body

    def reply(self, answer):
        choice = answer["choices"][0]
        finish = choice.get("finish_reason") or "length"
        return Reply(choice["text"], None, "length" if finish == "length" else "stop")

    def tokenize(self, text):
        return "/extras/tokenize", {"input": text}


#: Tried in this order: llama-server also answers ``/v1/models``.
DIALECTS: tuple[Dialect, ...] = (LlamaServer(), Vllm(), LlamaCppPythonServer())

SUPPORTED = "llama-server, python -m llama_cpp.server or vllm serve"


def probe(connection: Connection) -> tuple[Dialect, Served]:
    """Which server answers at an endpoint, and what it says about itself."""
    asked: dict[str, Any] = {}

    def get(path: str) -> Any:
        if path not in asked:
            status, answer = connection.call("GET", path)
            asked[path] = answer if status == 200 else None
        return asked[path]

    for dialect in DIALECTS:
        try:
            served = dialect.recognize(get)
        except Unsupported as exc:
            raise UserError(f"{connection.url} is {dialect.name}, but {exc}") from exc
        if served is not None:
            return dialect, served
    if _first_model(get) is not None:
        raise UserError(f"{connection.url} is an OpenAI-compatible server, but not one whose grammar field the planner "
                        f"knows (SGLang's, for one, is not supported yet): start {SUPPORTED} there")
    raise UserError(f"{connection.url} answers, but neither as llama-server (GET /props) nor as an OpenAI-compatible "
                    f"server (GET /v1/models): start {SUPPORTED} there")
