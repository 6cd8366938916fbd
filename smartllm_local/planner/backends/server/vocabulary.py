"""The served model's vocabulary: its tokenizer and chat template, on the planner's side of the wire.

The planner fits prompts, spells forced text and applies the chat template itself, so it needs the
served model's own tokenizer: read from a copy of its GGUF file (``vocab_only``: the metadata, not the
weights), from a Hugging Face tokenizer folder (a vLLM-served checkpoint's), or asked of llama-server
(``/tokenize``, ``/props``) where the model is on another machine. A vocabulary that is not the served
model's is refused before anything runs.
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, Protocol

from ....errors import UserError
from ..base import continuation_tokens
from ..llamacpp import LlamaCppBackend
from .connection import Connection, ServerError
from .dialects import Dialect, Served


class Vocabulary(Protocol):
    """The served model's tokenizer and chat template."""

    model: str
    chat_template: str | None
    bos_token: str
    eos_token: str
    end_tokens: frozenset[int]  # the tokens that end a sequence (llama.cpp's end-of-generation tokens)
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
        self.end_tokens = self._llama.end_tokens

    def bos_added(self) -> int | None:
        return self._llama.llm.token_bos() if self._llama.adds_bos() else None


#: Texts llama.cpp ends a generation at wherever they are one token of a vocabulary, besides the model's end of
#: sequence (its end-of-generation set: ends of turn, and the fill-in-the-middle separators code models have).
END_OF_TURN_TEXTS = ("<|eot_id|>", "<|eom_id|>", "<|im_end|>", "<|end|>", "<|return|>", "<|call|>", "<end_of_turn>",
                     "<|endoftext|>", "<|end_of_text|>", "<EOT>", "_<EOT>", "<\uff5cend\u2581of\u2581sentence\uff5c>",
                     "</s>", "<|fim_pad|>", "<fim-pad>", "<fim_pad>", "<|repo_name|>", "<reponame>",
                     "<|file_sep|>")


def end_tokens_by_rule(tokenize: Callable[..., list[int]], eos_token: str) -> frozenset[int]:
    """The end-of-generation tokens of a vocabulary known only through its tokenizer, by llama.cpp's rule."""
    ends = set()
    for text in {eos_token, *END_OF_TURN_TEXTS} - {""}:
        found = tokenize(text, special=True)
        if len(found) == 1:
            ends.add(found[0])
    return frozenset(ends)


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
    def end_tokens(self) -> frozenset[int]:
        """The tokens the server ends a generation at, by llama.cpp's rule: the model's end of sequence and
        each of the end-of-turn texts that is one token of this vocabulary."""
        return end_tokens_by_rule(self.tokenize, self.eos_token)

    @functools.cached_property
    def _bos(self) -> int | None:
        with_bos, without = self.tokenize("a", bos=True), self.tokenize("a")
        return with_bos[0] if len(with_bos) > len(without) else None

    def bos_added(self) -> int | None:
        return self._bos  # asked once per worker: the server is asked once


def open_vocabulary(model: str | Path) -> Vocabulary:
    """The vocabulary of ``--model``: a GGUF file (or an embedded model's name), or a Hugging Face folder."""
    from ...models import checkpoint_folder, resolve_gguf
    from ..hf_vocabulary import HFVocabulary

    folder = checkpoint_folder(str(model))
    return HFVocabulary.load(folder) if folder else LocalVocabulary(resolve_gguf(str(model)))


def served_vocabulary(model: str | None, served: Served, connection: Connection, dialect: Dialect) -> Vocabulary:
    """The served model's vocabulary: from ``--model``, else from the file or folder the server names where
    it is on this machine, else from the server itself (llama-server)."""
    if model is not None:
        return open_vocabulary(model)
    if served.model is not None and Path(served.model).exists():
        return open_vocabulary(served.model)
    if dialect.serves_vocabulary:
        return RemoteVocabulary(Connection(connection.url, connection.timeout), served.props)
    raise UserError(f"the vocabulary of the model served at {connection.url} cannot be read here: pass --model with a "
                    "copy of the served GGUF file, or for vLLM a folder with the checkpoint's tokenizer files (only "
                    "the vocabulary and chat template are read, not the weights)")


def check_vocabulary(vocabulary: Vocabulary, connection: Connection, dialect: Dialect) -> None:
    """Refuse a ``--model`` whose tokenizer is not the served model's: its budgets and tokens would be wrong."""
    probe_text = "Robots: GoToObject(robots[0], 'Fridge') # 3 steps\n"
    status, answer = connection.call("POST", *dialect.tokenize(probe_text))
    if status != 200 or not isinstance(answer, dict) or "tokens" not in answer:
        return  # a server without a tokenizer endpoint: nothing to compare with
    theirs = [t if isinstance(t, int) else t.get("id") for t in answer["tokens"]]
    ours = vocabulary.tokenize(probe_text)
    if theirs[-len(ours):] != ours:  # llama-cpp-python's endpoint puts BOS in front
        raise UserError(f"the server at {connection.url} tokenizes text differently from {vocabulary.model}: "
                        "pass --model with the served model's GGUF file or tokenizer folder")
