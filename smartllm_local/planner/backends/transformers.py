"""The transformers backend: Hugging Face checkpoints (or a GGUF file) on torch, grammars by llguidance.

For people who hold Hugging Face checkpoints rather than GGUF files. The
same GBNF grammars as llama.cpp's are compiled by llguidance into a token
mask at every step (llguidance is the engine outlines uses for grammars; it
is called directly, so there is no silent unconstrained fallback). A folder
with a ``config.json`` loads as a checkpoint; a ``.gguf`` file loads through
transformers' GGUF reader (dequantized). The key/value cache of
the last context is kept, so a context that extends it only runs the new
tokens. Nothing is fetched from a hub: the offline switches are set before
transformers is imported.

Devices: for this backend ``--n-gpu-layers`` is all-or-nothing (there is no
partial offload as in llama.cpp). 0 (the default) runs on the CPU in float32;
any other value (llama.cpp's -1 included) puts the whole model on the CUDA GPU
(``cuda``, or ``cuda:$LOCAL_RANK``) in bfloat16, or float16 where the GPU has no
bfloat16, and fails with a clear error when the installed torch has no CUDA.
Every tensor given to the model (the input ids; the key/value cache the model
makes) is on the model's device; the last position's logits are copied to the
CPU, where the decoding loop (:mod:`..decoding.loop`) chooses the token under
llguidance's mask (which llguidance fills through a CPU pointer).
Loading shows no progress bars; transformers' warnings still show.
"""

from __future__ import annotations

import contextlib
import copy
import importlib
import importlib.util
import logging
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import BackendUnavailableError, ModelError
from ..decoding import loop
from ..decoding.grammar import Grammar
from ..decoding.sampling import Generated, Sampling
from ..models import EMBEDDED, default_model, embedded_model_path, is_gguf
from .base import shared_prefix
from .hf_vocabulary import EXTRA as _EXTRA
from .hf_vocabulary import HFVocabulary
from .llguidance_grammar import LLGuidanceGrammar
from .prefix_cache import MemoryStates, PrefixReuse

for _switch in ("HF_HUB_OFFLINE", "TRANSFORMERS_OFFLINE", "HF_DATASETS_OFFLINE"):
    os.environ[_switch] = "1"

# Said by transformers whenever a GGUF is loaded in another dtype than float32, also for architectures it
# dequantizes anyway (llama, gemma3); the dtype is this backend's choice and the user cannot act on it.
_PACKED_DTYPE_NOTICE = "Loading a GGUF checkpoint with its weights packed is fastest in float32"


def _locate(model: str | None) -> tuple[Path, str | None]:
    """(folder, gguf file name or None) for a model argument."""
    model = model or default_model()
    if model in EMBEDDED:
        path = embedded_model_path(model)
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


def _placement(torch: Any, n_gpu_layers: int) -> tuple[Any, str | None]:
    """(dtype, device_map) for ``--n-gpu-layers``: all on the CPU in float32 (0), or all on the GPU."""
    if not n_gpu_layers:
        return torch.float32, None
    if not torch.cuda.is_available():
        if torch.version.cuda is None:
            why = f"the installed torch {torch.__version__} has no CUDA support (a CPU-only build)"
            fix = "or install a CUDA build of torch"
        else:
            why = (f"torch {torch.__version__} (CUDA {torch.version.cuda}) finds no usable GPU "
                   "(no NVIDIA driver, or CUDA_VISIBLE_DEVICES hides it)")
            fix = "or fix the driver"
        raise BackendUnavailableError(
            f"--n-gpu-layers {n_gpu_layers} asks the transformers backend for a GPU, but {why}; "
            f"run on the CPU with --n-gpu-layers 0, {fix}")
    return (torch.bfloat16 if torch.cuda.is_bf16_supported() else torch.float16), "cuda"


def _one_line(exc: BaseException, limit: int = 240) -> str:
    text = (str(exc).strip().splitlines() or [""])[0]
    cls = type(exc)
    kind = cls.__qualname__ if cls.__module__ == "builtins" else f"{cls.__module__}.{cls.__qualname__}"
    text = f"{kind}: {text}" if text else kind
    return text if len(text) <= limit else text[: limit - 3] + "..."


class _DropNotice(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        return not str(record.msg).startswith(_PACKED_DTYPE_NOTICE)


@contextlib.contextmanager
def _quiet_loading(transformers: Any):
    """No progress bars while loading; transformers' warnings still show.

    The GGUF reader calls ``tqdm.auto.tqdm`` directly ("Converting and de-quantizing GGUF tensors"),
    which transformers' progress-bar switch does not reach: it is pointed at transformers' own tqdm,
    which obeys the switch, for the duration of the load.
    """
    log = transformers.utils.logging
    was_enabled = log.is_progress_bar_enabled()
    log.disable_progress_bar()
    try:
        gguf_utils = importlib.import_module("transformers.modeling_gguf_pytorch_utils")
    except ImportError:
        gguf_utils = None
    original = getattr(gguf_utils, "tqdm", None)
    if original is not None:
        gguf_utils.tqdm = log.tqdm
    notice_logger = logging.getLogger("transformers.quantizers.quantizer_gguf")
    notice_filter = _DropNotice()
    notice_logger.addFilter(notice_filter)
    try:
        yield
    finally:
        notice_logger.removeFilter(notice_filter)
        if original is not None:
            gguf_utils.tqdm = original
        if was_enabled:
            log.enable_progress_bar()


class TransformersBackend(PrefixReuse):
    name = "transformers"

    def __init__(self, model: str | None, *, n_ctx: int = 8192, threads: int | None = None, n_gpu_layers: int = 0,
                 seed: int = 0):
        try:
            import llguidance
            import llguidance.hf
            import llguidance.torch  # noqa: F401  (the grammar's mask: fail here, with the fix)
            import torch
            import transformers
        except ImportError as exc:
            raise BackendUnavailableError(f"the transformers backend needs extra packages: {_EXTRA}") from exc
        self._torch, self._llg = torch, llguidance
        folder, gguf = _locate(model)
        self.model = str(folder / gguf) if gguf else str(folder)
        if gguf:
            missing = [name for name in ("gguf", "accelerate") if importlib.util.find_spec(name) is None]
            if missing:
                raise BackendUnavailableError(
                    f"loading a GGUF file with transformers needs {' and '.join(missing)}: {_EXTRA}")
        dtype, device_map = _placement(torch, n_gpu_layers)
        if threads:
            torch.set_num_threads(threads)
        torch.manual_seed(seed)
        self.tokenizer, self.lm, self.vocabulary = _load(transformers, torch, self.model, folder, gguf, dtype,
                                                         device_map)
        self.device = self.lm.get_input_embeddings().weight.device
        self.lm.eval()
        limit = getattr(self.lm.config, "max_position_embeddings", n_ctx) or n_ctx
        self.n_ctx = min(n_ctx, int(limit))
        self.ll_tokenizer = self.vocabulary.ll_tokenizer
        self.n_vocab = self.ll_tokenizer.vocab_size
        self.end_tokens = self.vocabulary.end_tokens
        self.token_bytes = self.vocabulary.piece
        self.chat_template = self.vocabulary.chat_template
        self.bos_token, self.eos_token = self.vocabulary.bos_token, self.vocabulary.eos_token
        self.tokenize, self.detokenize = self.vocabulary.tokenize, self.vocabulary.detokenize
        self.tokenize_continuation = self.vocabulary.tokenize_continuation
        self._tokens: list[int] = []
        self._states = MemoryStates()
        self.evaluated_tokens = 0
        self._cache: Any = None
        self._last: Any = None  # the last token's logits, on the model's device

    def evaluate(self, tokens: list[int]) -> None:
        torch = self._torch
        with torch.no_grad():
            ids = torch.tensor([tokens], dtype=torch.long, device=self.device)
            out = self.lm(input_ids=ids, past_key_values=self._cache, use_cache=True)
        self._cache = out.past_key_values
        self._last = out.logits[0, -1, :].float()
        self._tokens.extend(tokens)
        self.evaluated_tokens += len(tokens)

    def sync(self, context: Sequence[int]) -> None:
        context = list(context)
        if len(context) >= self.n_ctx:
            raise ModelError(f"the context ({len(context)} tokens) does not fit n_ctx={self.n_ctx}")
        common = shared_prefix(self._tokens, context)
        if common == len(context) == len(self._tokens) and self._last is not None:
            return
        self._truncate(min(common, len(context) - 1))
        self.evaluate(context[len(self._tokens):])

    def _truncate(self, size: int) -> None:
        """Keep the first ``size`` tokens of the cache."""
        if self._cache is not None and size > 0:
            surplus = len(self._tokens) - size
            if surplus:
                self._cache.crop(-surplus)  # transformers 5 takes the number of tokens to drop, negated
        else:
            self._cache, size = None, 0
        self._tokens = self._tokens[:size]
        self._last = None

    # prefixes (see PrefixReuse): kept in memory for this process, copied on the model's device; the store on
    # disk is llama.cpp's
    prefix_store = None
    keeps_states = True

    def _snapshot(self) -> Any:
        return copy.deepcopy(self._cache)

    def _restore(self, prefix: list[int], state: Any) -> bool:
        self._cache, self._tokens, self._last = copy.deepcopy(state), list(prefix), None
        return True

    def _state_size(self, state: Any) -> int:
        return sum(t.nbytes for layer in state.layers for t in (layer.keys, layer.values) if t is not None)

    def generate(self, context: Sequence[int], *, grammar: Grammar | None, max_tokens: int, sampling: Sampling,
                 stop: Sequence[str] = (), rng: np.random.Generator | None = None, lines: int = 1) -> Generated:
        """See :meth:`.base.Backend.generate`."""
        return loop.generate(self, context, grammar=grammar, max_tokens=max_tokens, sampling=sampling, stop=stop,
                             rng=rng, lines=lines)

    def next_logits(self) -> np.ndarray:
        return self._last[: self.n_vocab].cpu().numpy()

    def constrain(self, grammar: Grammar) -> LLGuidanceGrammar:
        return LLGuidanceGrammar(self._llg, self.ll_tokenizer, self.n_vocab, grammar)

    def first_bytes(self) -> None:
        """None: llguidance masks the whole vocabulary at once."""
        return None

    def close(self) -> None:
        self._cache = self._last = None
        self.lm = None
        if getattr(self, "device", None) is not None and self.device.type == "cuda":
            self._torch.cuda.empty_cache()


def _load(transformers: Any, torch: Any, model: str, folder: Path, gguf: str | None, dtype: Any,
          device_map: Any) -> tuple[Any, Any, HFVocabulary]:
    """The tokenizer, the model and its vocabulary, or an error that says what is wrong with the files and
    what to do."""
    kwargs: dict[str, Any] = {"local_files_only": True}
    if gguf:
        kwargs["gguf_file"] = gguf
    what = "GGUF file" if gguf else "Hugging Face checkpoint"
    try:
        with _quiet_loading(transformers):
            tokenizer = transformers.AutoTokenizer.from_pretrained(str(folder), **kwargs)
            lm = transformers.AutoModelForCausalLM.from_pretrained(
                str(folder), dtype=dtype, device_map=device_map, **kwargs)
            return tokenizer, lm, HFVocabulary(tokenizer, model)
    except (MemoryError, getattr(torch, "OutOfMemoryError", MemoryError)) as exc:
        where = "GPU memory (run on the CPU with --n-gpu-layers 0)" if device_map else "memory"
        raise ModelError(f"{model} does not fit in {where} ({_one_line(exc)}); use a smaller model") from exc
    except ImportError as exc:
        raise BackendUnavailableError(f"transformers could not load {model} ({_one_line(exc)}): {_EXTRA}") from exc
    except Exception as exc:  # the readers fail in many ways on a damaged file (struct.error, KeyError, ...)
        if device_map and "cuda" in str(exc).lower():
            raise ModelError(f"loading {model} on the GPU failed ({_one_line(exc)}); "
                             "run on the CPU with --n-gpu-layers 0") from exc
        fix = ("it may be truncated or corrupt (download it again) or of an architecture transformers "
               "cannot read (try --backend llamacpp)") if gguf else \
              "its files may be incomplete or corrupt (config.json, tokenizer and weights must all be there)"
        raise ModelError(f"{model} is not a readable {what} for the transformers backend "
                         f"({_one_line(exc)}); {fix}") from exc
