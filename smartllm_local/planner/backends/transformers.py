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
makes) is on the model's device, and so are the logits and the grammar's mask
applied to them; only llguidance's packed bitmask (which llguidance fills
through a CPU pointer) and temperature sampling (numpy) live on the CPU.
Loading shows no progress bars; transformers' warnings still show.
"""

from __future__ import annotations

import contextlib
import copy
import importlib
import importlib.util
import logging
import math
import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import BackendUnavailableError, GrammarMismatchError, ModelError
from ..decoding.grammar import Grammar, GrammarError
from ..decoding.matcher import Matcher
from ..models import EMBEDDED, default_model, embedded_model_path, is_gguf
from .base import Generated, Sampling, may_end, shared_prefix
from .hf_vocabulary import EXTRA as _EXTRA
from .hf_vocabulary import HFVocabulary
from .prefix_cache import MemoryStates, PrefixReuse
from .repetition import TRIES, current_line, draw

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
            import llguidance.torch
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
        kwargs: dict[str, Any] = {"local_files_only": True}
        if gguf:
            kwargs["gguf_file"] = gguf
        what = "GGUF file" if gguf else "Hugging Face checkpoint"
        try:
            with _quiet_loading(transformers):
                self.tokenizer = transformers.AutoTokenizer.from_pretrained(str(folder), **kwargs)
                self.lm = transformers.AutoModelForCausalLM.from_pretrained(
                    str(folder), dtype=dtype, device_map=device_map, **kwargs)
                self.vocabulary = HFVocabulary(self.tokenizer, self.model)
        except (MemoryError, getattr(torch, "OutOfMemoryError", MemoryError)) as exc:
            where = "GPU memory (run on the CPU with --n-gpu-layers 0)" if device_map else "memory"
            raise ModelError(f"{self.model} does not fit in {where} ({_one_line(exc)}); use a smaller model") from exc
        except ImportError as exc:
            raise BackendUnavailableError(
                f"transformers could not load {self.model} ({_one_line(exc)}): {_EXTRA}") from exc
        except Exception as exc:  # the readers fail in many ways on a damaged file (struct.error, KeyError, ...)
            if device_map and "cuda" in str(exc).lower():
                raise ModelError(f"loading {self.model} on the GPU failed ({_one_line(exc)}); "
                                 "run on the CPU with --n-gpu-layers 0") from exc
            fix = ("it may be truncated or corrupt (download it again) or of an architecture transformers "
                   "cannot read (try --backend llamacpp)") if gguf else \
                  "its files may be incomplete or corrupt (config.json, tokenizer and weights must all be there)"
            raise ModelError(f"{self.model} is not a readable {what} for the transformers backend "
                             f"({_one_line(exc)}); {fix}") from exc
        self.device = self.lm.get_input_embeddings().weight.device
        self.lm.eval()
        limit = getattr(self.lm.config, "max_position_embeddings", n_ctx) or n_ctx
        self.n_ctx = min(n_ctx, int(limit))
        self.ll_tokenizer = self.vocabulary.ll_tokenizer
        self.n_vocab = self.ll_tokenizer.vocab_size
        self.eos = self.tokenizer.eos_token_id
        self.chat_template = self.vocabulary.chat_template
        self.bos_token, self.eos_token = self.vocabulary.bos_token, self.vocabulary.eos_token
        self.tokenize, self.detokenize = self.vocabulary.tokenize, self.vocabulary.detokenize
        self.tokenize_continuation = self.vocabulary.tokenize_continuation
        self._tokens: list[int] = []
        self._states = MemoryStates()
        self.evaluated_tokens = 0
        self._cache: Any = None
        self._logits: Any = None

    def _evaluate(self, tokens: list[int]) -> None:
        torch = self._torch
        with torch.no_grad():
            ids = torch.tensor([tokens], dtype=torch.long, device=self.device)
            out = self.lm(input_ids=ids, past_key_values=self._cache, use_cache=True)
        self._cache = out.past_key_values
        self._logits = out.logits[0, -1, :].float()  # on the model's device
        self._tokens.extend(tokens)
        self.evaluated_tokens += len(tokens)

    def _sync(self, context: Sequence[int]) -> None:
        context = list(context)
        if len(context) >= self.n_ctx:
            raise ModelError(f"the context ({len(context)} tokens) does not fit n_ctx={self.n_ctx}")
        common = shared_prefix(self._tokens, context)
        if common == len(context) == len(self._tokens) and self._logits is not None:
            return
        self._truncate(min(common, len(context) - 1))
        self._evaluate(context[len(self._tokens):])

    def _truncate(self, size: int) -> None:
        """Keep the first ``size`` tokens of the cache."""
        if self._cache is not None and size > 0:
            surplus = len(self._tokens) - size
            if surplus:
                self._cache.crop(-surplus)  # transformers 5 takes the number of tokens to drop, negated
        else:
            self._cache, size = None, 0
        self._tokens = self._tokens[:size]
        self._logits = None

    # prefixes (see PrefixReuse): kept in memory for this process, copied on the model's device; the store on
    # disk is llama.cpp's
    prefix_store = None
    keeps_states = True

    def _snapshot(self) -> Any:
        return copy.deepcopy(self._cache)

    def _restore(self, prefix: list[int], state: Any) -> bool:
        self._cache, self._tokens, self._logits = copy.deepcopy(state), list(prefix), None
        return True

    def _state_size(self, state: Any) -> int:
        return sum(t.nbytes for layer in state.layers for t in (layer.keys, layer.values) if t is not None)

    def generate(self, context: Sequence[int], *, grammar: Grammar | None, max_tokens: int, sampling: Sampling,
                 stop: Sequence[str] = (), rng: np.random.Generator | None = None, lines: int = 1) -> Generated:
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
            mask = llg.torch.allocate_token_bitmask(1, self.n_vocab)  # on the CPU: llguidance fills it there
        guard = sampling.loop_guard
        follow = Matcher(grammar) if grammar is not None else None  # the planner's own reading of the text
        out = Generated([], "", "length")
        while len(out.tokens) < max_tokens:
            new = self._forced_tokens(follow, sampling) if follow is not None else []
            out.forced += len(new)
            if not new:
                raw = self._logits[: self.n_vocab]
                logits = raw.clone().unsqueeze(0)
                if matcher is not None:
                    # llguidance's own apply function goes through torch.compile (seconds per call): unpack here.
                    llg.torch.fill_next_token_bitmask(matcher, mask, 0)
                    bits = np.unpackbits(mask.numpy().view(np.uint8), bitorder="little")[: self.n_vocab]
                    blocked = torch.from_numpy(bits == 0).to(logits.device)
                    logits[0, blocked] = -float("inf")
                    if sampling.aligned and may_end(raw, self.eos):
                        logits[0, self.eos] = raw[self.eos]  # the end of sequence is the model's to choose
                token = self._pick(logits[0], sampling, rng)
                new = [token]
                line = current_line(out.text)
                if guard is not None and guard.loops(line + self.detokenize([token])):
                    # A loop (see LoopGuard): end the free text it runs in, or else avoid the looping token.
                    way = follow.shortest_way() if follow is not None else ""
                    out.loops += 1
                    if way:
                        new = self.tokenize_continuation(way)
                        out.forced += len(new)
                    else:
                        new = [self._pick(logits[0], sampling, rng,
                                          lambda t: guard.loops(line + self.detokenize([t])))]
                if len(new) == 1 and new[0] == token:
                    self._measure(out, raw, token, logits[0])
                if new[0] == self.eos or (matcher is not None and matcher.is_stopped()):
                    out.text, out.stop = self.detokenize(out.tokens), "eos"
                    return out
            for t in new:
                if matcher is not None and not matcher.consume_token(t):
                    raise GrammarMismatchError(out.text + self.detokenize(new), "the planner's grammar forces it, "
                                               f"llguidance refuses it: {matcher.get_error()}")
            out.tokens.extend(new)
            self._evaluate(new)
            piece = self.detokenize(new)
            if follow is not None and not follow.advance(piece):
                raise GrammarMismatchError(out.text + piece, "llguidance let the model write it, the planner's "
                                           "grammar does not allow it")
            out.text = self.detokenize(out.tokens)
            if matcher is not None and out.text.count("\n") >= lines:
                out.stop = "line"
                return out
            for s in stop:
                if s in out.text:
                    out.text, out.stop = out.text[: out.text.index(s)], "stop"
                    return out
        out.text = self.detokenize(out.tokens)
        return out

    def _forced_tokens(self, follow: Matcher, sampling: Sampling) -> list[int]:
        """As the llama.cpp backend does: the tokens of text the grammar forces, in one batch, but the last, which
        the model writes (unless decoding is not aligned); one character is left to the model altogether."""
        forced = follow.forced()
        if len(forced) < 2:
            return []
        tokens = self.tokenize_continuation(forced)
        return tokens[:-1] if sampling.aligned else tokens

    def _measure(self, out: Generated, raw: Any, token: int, masked: Any) -> None:
        """Whether the model's likeliest token was refused, and the chosen one's log-probability (unconstrained)."""
        best = int(self._torch.argmax(raw))
        out.choices += 1
        out.refused += best != token and not math.isfinite(float(masked[best]))
        out.logprob += float(self._torch.log_softmax(raw.double(), dim=-1)[token])

    def _pick(self, logits: Any, sampling: Sampling, rng: np.random.Generator,
              avoid: Callable[[int], bool] | None = None) -> int:
        """Greedy or sampled from the (grammar-masked) logits; ``avoid`` refuses tokens while others are left."""
        if sampling.temperature <= 0:
            if avoid is None:
                return int(self._torch.argmax(logits))
            order = self._torch.argsort(logits, descending=True, stable=True)[:TRIES].tolist()
            finite = [t for t in order if math.isfinite(float(logits[t]))]
            return next((t for t in finite if not avoid(t)), finite[0])
        scores = (logits / sampling.temperature).double().cpu().numpy()
        finite = np.isfinite(scores)
        return draw(np.where(finite, np.exp(scores - scores[finite].max()), 0.0), rng, avoid, TRIES)

    def close(self) -> None:
        self._cache = self._logits = None
        self.lm = None
        if getattr(self, "device", None) is not None and self.device.type == "cuda":
            self._torch.cuda.empty_cache()
