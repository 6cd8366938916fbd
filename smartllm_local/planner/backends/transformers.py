"""The transformers backend: Hugging Face checkpoints (or a GGUF file) on torch, grammars by llguidance.

For people who hold Hugging Face checkpoints rather than GGUF files. The
same GBNF grammars as llama.cpp's are compiled by llguidance into a token
mask at every step (llguidance is the engine outlines uses for grammars; it
is called directly, so there is no silent unconstrained fallback). A folder
with a ``config.json`` loads as a checkpoint; a ``.gguf`` file loads through
transformers' GGUF reader (dequantized to float32). The key/value cache of
the last context is kept, so a context that extends it only runs the new
tokens. Nothing is fetched from a hub: the offline switches are set before
transformers is imported.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ...errors import BackendUnavailableError, ModelError
from ..grammar import Grammar, GrammarError
from ..models import EMBEDDED, embedded_model_path, is_gguf
from .base import Generated, Sampling, shared_prefix

for _switch in ("HF_HUB_OFFLINE", "TRANSFORMERS_OFFLINE", "HF_DATASETS_OFFLINE"):
    os.environ[_switch] = "1"

_EXTRA = "pip install 'smartllm-local[transformers]' (torch, transformers, gguf, accelerate, llguidance)"


def _locate(model: str | None) -> tuple[Path, str | None]:
    """(folder, gguf file name or None) for a model argument."""
    if model is None or model in EMBEDDED:
        path = embedded_model_path(model or "smollm2")
        return path.parent, path.name
    path = Path(model).expanduser()
    if not path.exists():
        raise ModelError(f"model {path} does not exist; pass a Hugging Face checkpoint folder (with config.json) "
                         f"or a .gguf file, or an embedded model: {', '.join(EMBEDDED)}")
    if path.is_dir():
        if not (path / "config.json").is_file():
            raise ModelError(f"{path} is not a Hugging Face checkpoint: it has no config.json")
        return path, None
    if not is_gguf(path):
        raise ModelError(f"model {path} is neither a checkpoint folder nor a GGUF file")
    return path.parent, path.name


class TransformersBackend:
    name = "transformers"

    def __init__(self, model: str | None, *, n_ctx: int = 4096, threads: int | None = None, seed: int = 0):
        try:
            import llguidance
            import llguidance.hf
            import llguidance.torch
            import torch
            import transformers
        except ImportError as exc:
            raise BackendUnavailableError(f"the transformers backend needs extra packages: {_EXTRA}") from exc
        self._torch, self._llg = torch, llguidance
        folder, gguf = _locate(model)
        self.model = str(folder / gguf) if gguf else str(folder)
        if threads:
            torch.set_num_threads(threads)
        torch.manual_seed(seed)
        kwargs: dict[str, Any] = {"local_files_only": True}
        if gguf:
            kwargs["gguf_file"] = gguf
        transformers.utils.logging.set_verbosity_error()
        transformers.utils.logging.disable_progress_bar()
        try:
            self.tokenizer = transformers.AutoTokenizer.from_pretrained(str(folder), **kwargs)
            self.lm = transformers.AutoModelForCausalLM.from_pretrained(str(folder), dtype=torch.float32, **kwargs)
        except (OSError, ValueError) as exc:
            raise ModelError(f"transformers could not load {self.model}: {exc}") from exc
        self.lm.eval()
        limit = getattr(self.lm.config, "max_position_embeddings", n_ctx) or n_ctx
        self.n_ctx = min(n_ctx, int(limit))
        self.ll_tokenizer = llguidance.hf.from_tokenizer(self.tokenizer)
        self.n_vocab = self.ll_tokenizer.vocab_size
        self.eos = self.tokenizer.eos_token_id
        self._tokens: list[int] = []
        self.evaluated_tokens = 0
        self._cache: Any = None
        self._logits: Any = None

    def tokenize(self, text: str, *, bos: bool = False) -> list[int]:
        return list(self.tokenizer(text, add_special_tokens=bos)["input_ids"])

    def detokenize(self, tokens: Sequence[int]) -> str:
        return self.tokenizer.decode(list(tokens), skip_special_tokens=True)

    def _forward(self, tokens: list[int]) -> None:
        torch = self._torch
        with torch.no_grad():
            out = self.lm(input_ids=torch.tensor([tokens]), past_key_values=self._cache, use_cache=True)
        self._cache = out.past_key_values
        self._logits = out.logits[0, -1, :].float()
        self._tokens.extend(tokens)
        self.evaluated_tokens += len(tokens)

    def _sync(self, context: Sequence[int]) -> None:
        context = list(context)
        if len(context) >= self.n_ctx:
            raise ModelError(f"the context ({len(context)} tokens) does not fit n_ctx={self.n_ctx}")
        common = shared_prefix(self._tokens, context)
        if common == len(context) == len(self._tokens) and self._logits is not None:
            return
        common = min(common, len(context) - 1)
        if self._cache is not None and common > 0:
            surplus = len(self._tokens) - common
            if surplus:
                self._cache.crop(-surplus)  # transformers 5 takes the number of tokens to drop, negated
        else:
            self._cache, common = None, 0
        self._tokens = self._tokens[:common]
        self._forward(context[common:])

    def generate(self, context: Sequence[int], *, grammar: Grammar | None, max_tokens: int, sampling: Sampling,
                 stop: Sequence[str] = (), rng: np.random.Generator | None = None) -> Generated:
        torch, llg = self._torch, self._llg
        rng = rng or np.random.default_rng(sampling.seed)
        max_tokens = min(max_tokens, self.n_ctx - len(context) - 1)
        self._sync(context)
        matcher = None
        mask = None
        if grammar is not None:
            matcher = llg.LLMatcher(self.ll_tokenizer, llg.grammar_from("gbnf", grammar.to_gbnf()))
            if matcher.is_error():
                raise GrammarError(f"llguidance rejected a grammar: {matcher.get_error()}")
            mask = llg.torch.allocate_token_bitmask(1, self.n_vocab)
        out: list[int] = []
        while len(out) < max_tokens:
            logits = self._logits[: self.n_vocab].clone().unsqueeze(0)
            if matcher is not None:
                # llguidance's own apply function goes through torch.compile (seconds per call): unpack here.
                llg.torch.fill_next_token_bitmask(matcher, mask, 0)
                bits = np.unpackbits(mask.numpy().view(np.uint8), bitorder="little")[: self.n_vocab]
                logits[0, torch.from_numpy(bits == 0)] = -float("inf")
            token = self._pick(logits[0], sampling, rng)
            if token == self.eos or (matcher is not None and matcher.is_stopped()):
                return Generated(out, self.detokenize(out), "eos")
            if matcher is not None and not matcher.consume_token(token):
                raise GrammarError(f"llguidance refused token {token}: {matcher.get_error()}")
            out.append(token)
            self._forward([token])
            text = self.detokenize(out)
            if matcher is not None and text.endswith("\n"):
                return Generated(out, text, "line")
            for s in stop:
                if s in text:
                    return Generated(out, text[: text.index(s)], "stop")
        return Generated(out, self.detokenize(out), "length")

    def _pick(self, logits: Any, sampling: Sampling, rng: np.random.Generator) -> int:
        if sampling.temperature <= 0:
            return int(self._torch.argmax(logits))
        scores = (logits / sampling.temperature).double().numpy()
        finite = np.isfinite(scores)
        probs = np.where(finite, np.exp(scores - scores[finite].max()), 0.0)
        probs /= probs.sum()
        return int(rng.choice(len(probs), p=probs))

    def close(self) -> None:
        self._cache = None
        self.lm = None
