"""A Hugging Face tokenizer as the planner's vocabulary: the transformers backend's, and a vLLM-served model's.

Tokens are spelled by their own bytes (llguidance's view of the tokenizer), not by Hugging Face's
``decode``, which drops a SentencePiece token's leading space at the start of what it decodes: wrong for
a continuation.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ...errors import BackendUnavailableError, ModelError
from .base import continuation_tokens

EXTRA = "pip install 'smartllm-local[transformers]' (torch, transformers, gguf, accelerate, llguidance)"


class HFVocabulary:
    """Tokens, control-token text and chat template of a loaded Hugging Face tokenizer."""

    def __init__(self, tokenizer: Any, model: str, trained_context: int | None = None):
        import llguidance.hf

        self.tokenizer, self.model, self.trained_context = tokenizer, model, trained_context
        self.ll_tokenizer = llguidance.hf.from_tokenizer(tokenizer)
        template = getattr(tokenizer, "chat_template", None)  # a dict where a checkpoint names several
        self.chat_template = template.get("default") if isinstance(template, dict) else template
        self.bos_token, self.eos_token = tokenizer.bos_token or "", tokenizer.eos_token or ""
        self.end_tokens = frozenset({tokenizer.eos_token_id} if tokenizer.eos_token_id is not None else ())

    @classmethod
    def load(cls, folder: Path) -> HFVocabulary:
        """The tokenizer of a checkpoint folder (its tokenizer files suffice), offline."""
        try:
            import llguidance.hf  # noqa: F401  (needed by the constructor: fail here, with the fix)
            import transformers
        except ImportError as exc:
            raise BackendUnavailableError(f"reading a Hugging Face tokenizer needs extra packages: {EXTRA}") from exc
        try:
            tokenizer = transformers.AutoTokenizer.from_pretrained(str(folder), local_files_only=True)
        except Exception as exc:  # transformers fails in many ways on a folder without a tokenizer
            raise ModelError(f"{folder} holds no Hugging Face tokenizer that transformers can read "
                             f"({type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''}); pass the "
                             "served model's checkpoint folder, or a folder with its tokenizer files") from exc
        return cls(tokenizer, str(folder), checkpoint_context(folder))

    def tokenize(self, text: str, *, bos: bool = False, special: bool = False) -> list[int]:
        return list(self.tokenizer(text, add_special_tokens=bos, split_special_tokens=not special)["input_ids"])

    def detokenize(self, tokens: Sequence[int]) -> str:
        return b"".join(self.piece(t) for t in tokens).decode("utf-8", errors="replace")

    def tokenize_continuation(self, text: str) -> list[int]:
        return continuation_tokens(text, self.tokenize, self.piece)

    def text_of(self, tokens: Sequence[int]) -> str:
        """The text that tokenizes back into ``tokens`` with control tokens parsed: those written out."""
        return "".join(self.tokenizer.convert_ids_to_tokens(t) if self.ll_tokenizer.is_special_token(t)
                       else self.piece(t).decode("utf-8", errors="replace") for t in tokens)

    def piece(self, token: int) -> bytes:
        """A token's bytes, control tokens none."""
        return b"" if self.ll_tokenizer.is_special_token(token) else self.ll_tokenizer.decode_bytes([token])

    def bos_added(self) -> int | None:
        """The token the tokenizer puts in front of a prompt, if it does."""
        with_bos, without = self.tokenize("a", bos=True), self.tokenize("a")
        return with_bos[0] if len(with_bos) > len(without) and with_bos[1:] == without else None


def checkpoint_context(folder: Path) -> int | None:
    """The context a checkpoint was trained on (its config.json's ``max_position_embeddings``), if it says."""
    try:
        value = json.loads((folder / "config.json").read_text()).get("max_position_embeddings")
    except (OSError, ValueError, AttributeError):
        return None
    return value if isinstance(value, int) and value > 0 else None
