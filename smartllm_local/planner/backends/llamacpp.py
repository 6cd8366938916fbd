"""The llama.cpp backend (llama-cpp-python), decoding with the planner's loop (:mod:`..decoding.loop`).

The key/value cache holds the last context; a new context that shares a
prefix with it only evaluates the rest. Tokens the decoding loop adds, and what the next call's context adds after
them, are evaluated when logits are next asked for (:class:`.LlamaDecoding`), so a token the model chose and the
text the grammar forces after it, across a line's end too, go into one batch, and each batch carries drafts from the
context (:mod:`.drafts`), kept where the model chooses them. A stage's prompt begins with its
examples, whose state (one sequence's key/value cells, llama.cpp's
``llama_state_seq_*``: no logits) is kept in memory and in an optional
:class:`PrefixStore` on disk, and the rest of a prompt is always evaluated on a
loaded state (see :class:`PrefixReuse`).

Several sequences decoded together in one batch are the :meth:`LlamaCppBackend.lanes` (see :mod:`.lanes`).
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import io
import os
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import BackendUnavailableError, ModelError
from .amx import amx_runs, without_extra_buffers
from .base import continuation_tokens, keep_whole
from .drafts import draft_size, lookup
from .llamacpp_decoding import LlamaDecoding, fill_batch
from .prefix_cache import MemoryStates, PrefixReuse, PrefixStore, state_key

CPU_BATCH, GPU_BATCH, UBATCH = 512, 2048, 512


def _trained_context(metadata: dict[str, str]) -> int | None:
    """The context the model was trained on, from its GGUF metadata (a vocabulary file has none)."""
    value = metadata.get(f"{metadata.get('general.architecture', '')}.context_length", "")
    return int(value) if value.isdigit() and int(value) > 0 else None


def gguf_trained_context(model_path: str | Path) -> int | None:
    """The context a GGUF model was trained on, read from its metadata by loading its vocabulary alone (no
    weights, no context worth the name): what a context size is checked against before the model loads."""
    _, llm, _ = _open(model_path, n_ctx=512, threads=1, n_gpu_layers=0, seed=0, n_batch=CPU_BATCH, vocab_only=True)
    try:
        return _trained_context(llm.metadata)
    finally:
        llm.close()


def _open(model_path: str | Path, *, n_ctx: int, threads: int, n_gpu_layers: int, seed: int, n_batch: int,
          vocab_only: bool) -> tuple[Any, Any, bool]:
    """llama-cpp-python, a model loaded in it, and whether it was loaded without llama.cpp's extra buffer types
    (AMX traps here: :mod:`.amx`); or a clear error where either cannot be had."""
    try:
        import llama_cpp
    except ImportError as exc:
        raise BackendUnavailableError("llama-cpp-python is not installed: pip install 'llama-cpp-python>=0.3.36'") \
            from exc
    # A vocabulary has no training context, which llama.cpp warns about on stderr as it loads one.
    quiet = contextlib.redirect_stderr(io.StringIO()) if vocab_only else contextlib.nullcontext()
    plain = not vocab_only and not amx_runs(llama_cpp, model_path)  # AMX traps on some virtual machines
    try:
        # On the CPU flash attention stays off: there it decoded Qwen2.5-Coder-1.5B 30% slower over the
        # benchmark's decompositions (docs/measurements.md); on a GPU llama.cpp decides (auto).
        with quiet, _flash_attention_auto(llama_cpp, wanted=bool(n_gpu_layers)), \
                without_extra_buffers(llama_cpp, wanted=plain):
            llm = llama_cpp.Llama(model_path=str(model_path), n_ctx=n_ctx, n_threads=threads, n_gpu_layers=n_gpu_layers,
                                  seed=seed, n_batch=n_batch, n_ubatch=UBATCH, logits_all=False, vocab_only=vocab_only,
                                  verbose=False)
            return llama_cpp, llm, plain
    except (ValueError, RuntimeError) as exc:
        raise ModelError(f"llama.cpp could not load {model_path}: {exc}") from exc


@contextlib.contextmanager
def _flash_attention_auto(llama_cpp, wanted: bool):
    """Where ``wanted``, make the context llama.cpp's own default, flash attention ``auto`` (on where the device
    runs it: on a GPU, where the build has its kernels), which llama-cpp-python 0.3.36 cannot ask for (its
    ``flash_attn`` is on or off): it reads its "off" from this constant while it makes the context."""
    if not wanted:
        yield
        return
    module = llama_cpp.llama_cpp
    off = module.LLAMA_FLASH_ATTN_TYPE_DISABLED
    module.LLAMA_FLASH_ATTN_TYPE_DISABLED = module.LLAMA_FLASH_ATTN_TYPE_AUTO
    try:
        yield
    finally:
        module.LLAMA_FLASH_ATTN_TYPE_DISABLED = off


class LlamaCppBackend(LlamaDecoding, PrefixReuse):
    """A GGUF model run by llama.cpp."""

    name = "llamacpp"

    def __init__(
        self,
        model_path: str | Path,
        *,
        n_ctx: int = 8192,
        threads: int | None = None,
        n_gpu_layers: int = 0,
        seed: int = 0,
        n_batch: int | None = None,
        vocab_only: bool = False,
        prefix_store: PrefixStore | None = None,
        drafts: bool = True,
    ):
        """``vocab_only`` loads the tokenizer alone (llama.cpp's vocabulary files): it tokenizes but cannot generate.
        ``prefix_store`` keeps the examples' states for later processes (None: this process only). ``n_batch``
        (tokens per evaluation call) follows the device unless given: llama.cpp's own 2,048 where layers are on a
        GPU, 512 on the CPU (whose speed it does not change); either way llama.cpp computes 512 at a time. ``drafts``:
        evaluate the tokens the loop adds when logits are asked for, with drafts from the context (see
        :mod:`.drafts`); off, each as it is added, alone or with those added with it."""
        self._n_batch = n_batch = n_batch or (GPU_BATCH if n_gpu_layers else CPU_BATCH)
        self._threads = threads or max(1, os.cpu_count() or 1)
        llama_cpp, self.llm, plain = _open(model_path, n_ctx=n_ctx, threads=self._threads, n_gpu_layers=n_gpu_layers,
                                    seed=seed, n_batch=n_batch, vocab_only=vocab_only)
        self._lib = llama_cpp
        self._vocab_only = vocab_only
        self.model = str(model_path)
        self.n_ctx = self.llm.n_ctx()
        self.n_vocab = self.llm.n_vocab()
        self._vocab = self.llm._model.vocab
        self._ctx = self.llm._ctx.ctx
        self._tokens: list[int] = []  # the context the key/value cache holds
        self._alone: list[bool] = []  # which of them were evaluated alone (a lone token computes otherwise)
        self._ahead: list[int] = []  # drafted tokens the cache holds after the context (none while any is pending)
        self._states = MemoryStates()
        self.prefix_store = prefix_store
        if not n_gpu_layers:  # on the CPU keeping states always pays (see PrefixReuse): measured on a GPU only
            self.keeps_states = self.stores_states = True
        self._settings = {"backend": self.name, "llama_cpp": getattr(llama_cpp, "__version__", ""), "n_ctx": n_ctx,
                          "n_batch": n_batch, "n_gpu_layers": n_gpu_layers,
                          "flash_attn": "auto" if n_gpu_layers else "off"}
        if plain:  # weights in plain buffers compute otherwise: their states are not AMX's
            self._settings["extra_buffers"] = False
        self.evaluated_tokens = 0  # context tokens run through the model so far (prefix reuse keeps this low)
        self.drafted_tokens = self.kept_drafts = 0  # drafts evaluated, and those the model then chose
        self._batch = None if vocab_only else self._lib.llama_batch_init(n_batch, 0, 1)
        self._pieces: dict[tuple[int, bool], bytes] = {}
        # The texts a grammar forces recur (`GoToObject(robot_list[`, a line's end): each spelled once.
        self._continuations = functools.lru_cache(maxsize=1024)(
            lambda text: tuple(continuation_tokens(text, self.tokenize, self._piece)))
        self._init_decoding(frozenset(t for t in range(self.n_vocab) if llama_cpp.llama_vocab_is_eog(self._vocab, t)),
                            drafts)
        self.n_gpu_layers = n_gpu_layers
        self.chat_template = self.llm.metadata.get("tokenizer.chat_template")
        # Prompts are fitted within what the model was trained on: a Llama-2 keeps 4,096 tokens.
        self.trained_context = _trained_context(self.llm.metadata)
        if self.trained_context and not vocab_only:
            self.n_ctx = min(self.n_ctx, self.trained_context)
        self.bos_token, self.eos_token = (self.llm._model.token_get_text(t) if t != -1 else ""
                                          for t in (self.llm.token_bos(), self.llm.token_eos()))

    # ---------------------------------------------------------------- tokens

    def tokenize(self, text: str, *, bos: bool = False, special: bool = False) -> list[int]:
        return list(self.llm.tokenize(text.encode("utf-8"), add_bos=bos, special=special))

    def detokenize(self, tokens: Sequence[int]) -> str:
        return b"".join(self._piece(t) for t in tokens).decode("utf-8", errors="replace")

    def tokenize_continuation(self, text: str) -> list[int]:
        return list(self._continuations(text))

    def text_of(self, tokens: Sequence[int]) -> str:
        """The text that tokenizes back into ``tokens`` with control tokens parsed (``<|im_start|>`` written
        out, not dropped as :meth:`detokenize` drops it): what a server that takes text is sent."""
        return b"".join(self._piece(t, special=True) for t in tokens).decode("utf-8", errors="replace")

    def adds_bos(self) -> bool:
        """Whether the model's tokenizer puts a beginning-of-sequence token in front of a prompt."""
        return self.llm.token_bos() != -1 and bool(self.llm._model.add_bos_token())

    def _piece(self, token: int, special: bool = False) -> bytes:
        """A token's bytes (llama-cpp-python's detokenize garbles pieces over 32 bytes, drops a space after BOS);
        ``special`` writes a control token's text rather than nothing."""
        key = (token, special)
        piece = self._pieces.get(key)
        if piece is None:
            size = 64
            while True:
                buffer = ctypes.create_string_buffer(size)
                n = self._lib.llama_token_to_piece(self._vocab, token, buffer, size, 0, special)
                if n >= 0:
                    break
                size = -n
            piece = self._pieces[key] = buffer.raw[:n]
        return piece

    def _held(self) -> list[int]:
        return self._tokens

    def _drafts(self) -> list[int]:
        return self._ahead

    def _restart(self, context: list[int], common: int) -> None:
        """Re-evaluate at least one token for its logits, and no part of a batch alone."""
        self._truncate(keep_whole(self._alone, min(common, len(context) - 1)))
        self.evaluate(context[len(self._tokens):])

    def _truncate(self, size: int) -> None:
        """Keep the first ``size`` tokens of the cache; the logits are stale until the next evaluation."""
        if size == 0:  # as new: a cache whose cells are laid out afresh computes as a new context does
            self._lib.llama_memory_clear(self._lib.llama_get_memory(self._ctx), True)
        else:
            self.llm._ctx.kv_cache_seq_rm(-1, size, -1)
        self._tokens, self._alone = self._tokens[:size], self._alone[:size]
        self._pending, self._ahead, self._rows = [], [], None

    # -------------------------------------------------------------- prefixes

    def _store_key(self, prefix: Sequence[int]) -> str:
        from ...provenance import sha256_file

        return state_key({**self._settings, "model": sha256_file(self.model)}, prefix)

    def _state_bytes(self) -> int:
        return int(self._lib.llama_state_seq_get_size(self._ctx, 0))

    def _snapshot(self) -> bytes:
        self._settle()
        self._without_drafts()
        size = self._state_bytes()
        buffer = (ctypes.c_uint8 * size)()
        written = self._lib.llama_state_seq_get_data(self._ctx, buffer, size, 0)
        return ctypes.string_at(buffer, written)

    def _restore(self, prefix: list[int], state: bytes) -> bool:
        self._truncate(0)
        source = ctypes.cast(state, ctypes.POINTER(ctypes.c_uint8))  # read in place, not copied
        if not self._lib.llama_state_seq_set_data(self._ctx, source, len(state), 0):
            self._truncate(0)
            return False
        self._tokens, self._alone = list(prefix), [False] * len(prefix)  # evaluated in batches
        return True

    def _state_size(self, state: bytes) -> int:
        return len(state)

    def _keep_drafts(self, count: int) -> None:
        self._tokens.extend(self._ahead[:count])
        self._alone.extend([False] * count)
        self._ahead = self._ahead[count:]
        self.evaluated_tokens += count
        self.kept_drafts += count

    def _drop_drafts(self) -> None:
        self.llm._ctx.kv_cache_seq_rm(-1, len(self._tokens), -1)
        self._ahead = []

    def _flush(self, drafts: bool) -> None:
        pending, self._pending = self._pending, []
        start = len(self._tokens)
        room = self.n_ctx - 1 - start - len(pending)
        size = min(draft_size(len(pending)), room) if drafts else 0
        ahead = lookup(self._tokens + pending, size) if size > 0 else []
        try:
            self._rows = self._decode(pending + ahead, start, first_row=len(pending) - 1)
        except ModelError:
            self._truncate(start)  # cells a failed batch left are not the context's
            raise
        self._tokens.extend(pending)
        self._alone.extend([len(pending) + len(ahead) == 1] * len(pending))
        self._ahead = ahead
        self.evaluated_tokens += len(pending)
        self.drafted_tokens += len(ahead)

    def _decode(self, tokens: Sequence[int], start: int, first_row: int) -> np.ndarray:
        """Evaluate ``tokens`` at positions from ``start`` in batches of ``n_batch``; the logits after each token
        from ``first_row`` on."""
        lib, batch, rows = self._lib, self._batch, []
        for offset in range(0, len(tokens), self._n_batch):
            chunk = tokens[offset:offset + self._n_batch]
            batch.n_tokens = fill_batch(batch, chunk, start + offset, logits_from=first_row - offset)
            if lib.llama_decode(self._ctx, batch) != 0:
                raise ModelError(f"llama.cpp could not evaluate {len(chunk)} tokens at position {start + offset}")
            for i in range(max(0, first_row - offset), len(chunk)):
                rows.append(np.ctypeslib.as_array(lib.llama_get_logits_ith(self._ctx, i), shape=(self.n_vocab,)).copy())
        lib.llama_synchronize(self._ctx)  # on a GPU evaluation runs on after decode returns
        return np.stack(rows)

    def engine_seconds(self, tokens: Sequence[int], n_batch: int = GPU_BATCH) -> float:
        """Seconds llama.cpp alone takes to evaluate ``tokens`` from an empty cache: a context of its own on the
        same weights with this backend's settings (threads, attention) but llama.cpp's default batches, the last
        token's logits only, after a warm-up. What ``bench`` measures :meth:`prefill` against."""
        lib = self._lib
        if not tokens:
            return 0.0
        ctx = self._new_context("the engine's own timing", n_ctx=min(self.n_ctx, -(-(len(tokens) + 8) // 256) * 256),
                                n_batch=n_batch, n_ubatch=UBATCH)
        batch = lib.llama_batch_init(n_batch, 0, 1)
        try:
            def run(chunk: Sequence[int], start: int, last: bool) -> None:
                batch.n_tokens = fill_batch(batch, chunk, start, logits_from=len(chunk) - 1 if last else len(chunk))
                if lib.llama_decode(ctx, batch) != 0:
                    raise ModelError("llama.cpp could not evaluate the engine's timing batch")

            run(tokens[:8], 0, True)  # the first call sets the device up: not timed
            lib.llama_synchronize(ctx)
            lib.llama_memory_clear(lib.llama_get_memory(ctx), True)
            started = time.perf_counter()
            for start in range(0, len(tokens), n_batch):
                run(tokens[start:start + n_batch], start, start + n_batch >= len(tokens))
            lib.llama_synchronize(ctx)
            return time.perf_counter() - started
        finally:
            lib.llama_batch_free(batch)
            lib.llama_free(ctx)

    def _new_context(self, purpose: str, **settings: int | bool) -> Any:
        """A second llama.cpp context on the same weights, with this backend's settings (threads, attention) but
        ``settings`` (fields of llama.cpp's context parameters); free it with ``llama_free``."""
        mine = self.llm.context_params
        params = type(mine).from_buffer_copy(mine)
        for name, value in settings.items():
            setattr(params, name, value)
        ctx = self._lib.llama_init_from_model(self.llm._model.model, params)
        if not ctx:
            raise ModelError(f"llama.cpp could not make a second context for {purpose} (out of memory?)")
        return ctx

    @contextlib.contextmanager
    def lanes(self, n: int, *, n_ctx: int | None = None, unified: bool = False) -> Iterator[list[Any]]:
        """``n`` views of this model that decode ``n`` sequences together, each from a thread of its own (see
        :mod:`.lanes`), in a context of their own that is freed on exit; this backend and its cache are left as
        they were. ``n_ctx``: the key/value cells of each lane (this backend's n_ctx unless given); ``unified``:
        instead, all lanes share ``n_ctx`` cells (a prefix they share is held once, not once per lane), and greedy
        lanes may then part from what this backend writes where two tokens are all but tied."""
        from .lanes import LaneEngine

        if self._vocab_only:
            raise ModelError("a vocabulary cannot generate: load the model's weights for lanes")
        engine = LaneEngine(self, n, n_ctx or self.n_ctx, unified)
        try:
            yield engine.views
        finally:
            engine.close()

    def close(self) -> None:
        batch, self._batch = getattr(self, "_batch", None), None
        if batch is not None:
            self._lib.llama_batch_free(batch)
        llm, self.llm = getattr(self, "llm", None), None
        if llm is not None:
            llm.close()
