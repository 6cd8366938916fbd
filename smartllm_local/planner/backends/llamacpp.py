"""The llama.cpp backend (llama-cpp-python), with a sampling loop of its own.

llama-cpp-python's sampler chain applies a grammar to the whole vocabulary at
every step: ~60 ms per token for Gemma-3's 262k tokens on two cores. Here the
grammar is asked first only about the likeliest tokens: greedy decoding takes
the likeliest token if the grammar admits it, else the best of the top 64 that
it admits (the same token a full mask would give, since any admitted token
outside the top 64 scores lower; finding the 64 costs 0.5 ms a step on
SmolLM2's vocabulary and 2.8 ms on Gemma-3's, so it is done only then), and
sampling draws from the full distribution and keeps the draw if the grammar
admits it (rejection sampling, which gives exactly the masked distribution).
Only when that fails is the full vocabulary masked.

Grammars are checked by llama.cpp before use: ``llama_sampler_init_grammar``
returns NULL for a bad one (llama-cpp-python 0.3.36 does not check, and a bad
grammar would crash the process at the first token).

The key/value cache holds the last context; a new context that shares a
prefix with it only evaluates the rest. A stage's prompt begins with its
examples, whose state (one sequence's key/value cells, llama.cpp's
``llama_state_seq_*``: no logits) is kept in memory and in an optional
:class:`PrefixStore` on disk, and the rest of a prompt is always evaluated on a
loaded state (see :class:`PrefixReuse`).

The text of generated tokens is their bytes, decoded as they come (a
character split across tokens is held back until complete), and it is
followed through the planner's own grammar: where that grammar does not
allow what llama.cpp's let through, or llama.cpp's refuses text the planner's
grammar forces, the two disagree and generation stops with an error.
"""

from __future__ import annotations

import codecs
import contextlib
import ctypes
import io
import os
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import BackendUnavailableError, GrammarMismatchError, ModelError
from ..decoding.grammar import Grammar, GrammarError
from ..decoding.matcher import Matcher
from .base import END_RANK, Generated, Sampling, continuation_tokens, keep_whole, may_end, shared_prefix
from .prefix_cache import MemoryStates, PrefixReuse, PrefixStore, state_key
from .repetition import TRIES, current_line, draw

_TOP = END_RANK  # the candidates looked at before the whole vocabulary is masked
CPU_BATCH, GPU_BATCH, UBATCH = 512, 2048, 512


def _trained_context(metadata: dict[str, str]) -> int | None:
    """The context the model was trained on, from its GGUF metadata (a vocabulary file has none)."""
    value = metadata.get(f"{metadata.get('general.architecture', '')}.context_length", "")
    return int(value) if value.isdigit() and int(value) > 0 else None


def gguf_trained_context(model_path: str | Path) -> int | None:
    """The context a GGUF model was trained on, read from its metadata by loading its vocabulary alone (no
    weights, no context worth the name): what a context size is checked against before the model loads."""
    _, llm = _open(model_path, n_ctx=512, threads=1, n_gpu_layers=0, seed=0, n_batch=CPU_BATCH, vocab_only=True)
    try:
        return _trained_context(llm.metadata)
    finally:
        llm.close()


def _open(model_path: str | Path, *, n_ctx: int, threads: int, n_gpu_layers: int, seed: int, n_batch: int,
          vocab_only: bool) -> tuple[Any, Any]:
    """llama-cpp-python and a model loaded in it, or a clear error where either cannot be had."""
    try:
        import llama_cpp
    except ImportError as exc:
        raise BackendUnavailableError("llama-cpp-python is not installed: pip install 'llama-cpp-python>=0.3.36'") \
            from exc
    # A vocabulary has no training context, which llama.cpp warns about on stderr as it loads one.
    quiet = contextlib.redirect_stderr(io.StringIO()) if vocab_only else contextlib.nullcontext()
    try:
        # On the CPU flash attention stays off: there it decoded Qwen2.5-Coder-1.5B 30% slower over the
        # benchmark's decompositions (docs/measurements.md); on a GPU llama.cpp decides (auto).
        with quiet, _flash_attention_auto(llama_cpp, wanted=bool(n_gpu_layers)):
            return llama_cpp, llama_cpp.Llama(model_path=str(model_path), n_ctx=n_ctx, n_threads=threads,
                                              n_gpu_layers=n_gpu_layers, seed=seed, n_batch=n_batch, n_ubatch=UBATCH,
                                              logits_all=False, vocab_only=vocab_only, verbose=False)
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


class LlamaCppBackend(PrefixReuse):
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
    ):
        """``vocab_only`` loads the tokenizer alone (llama.cpp's vocabulary files): it tokenizes but cannot generate.
        ``prefix_store`` keeps the examples' states for later processes (None: this process only). ``n_batch``
        (tokens per evaluation call) follows the device unless given: llama.cpp's own 2,048 where layers are on a
        GPU, 512 on the CPU (whose speed it does not change); either way llama.cpp computes 512 at a time."""
        n_batch = n_batch or (GPU_BATCH if n_gpu_layers else CPU_BATCH)
        self._threads = threads or max(1, os.cpu_count() or 1)
        llama_cpp, self.llm = _open(model_path, n_ctx=n_ctx, threads=self._threads, n_gpu_layers=n_gpu_layers,
                                    seed=seed, n_batch=n_batch, vocab_only=vocab_only)
        self._lib = llama_cpp
        self.model = str(model_path)
        self.n_ctx = self.llm.n_ctx()
        self.n_vocab = self.llm.n_vocab()
        self._vocab = self.llm._model.vocab
        self._ctx = self.llm._ctx.ctx
        self._tokens: list[int] = []  # what the key/value cache holds
        self._alone: list[bool] = []  # which of them were evaluated alone (a lone token computes otherwise)
        self._states = MemoryStates()
        self._ends = True  # whether the end of sequence is always admitted (Sampling.aligned)
        self.prefix_store = prefix_store
        if not n_gpu_layers:  # on the CPU keeping states always pays (see PrefixReuse): measured on a GPU only
            self.keeps_states = self.stores_states = True
        self._settings = {"backend": self.name, "llama_cpp": getattr(llama_cpp, "__version__", ""), "n_ctx": n_ctx,
                          "n_batch": n_batch, "n_gpu_layers": n_gpu_layers,
                          "flash_attn": "auto" if n_gpu_layers else "off"}
        self.evaluated_tokens = 0  # tokens run through the model so far (prefix reuse keeps this low)
        self._fresh = False  # whether the logits belong to the last token of _tokens
        self._pieces: dict[tuple[int, bool], bytes] = {}
        self._eog = np.array([bool(llama_cpp.llama_vocab_is_eog(self._vocab, t)) for t in range(self.n_vocab)])
        self.end_tokens = frozenset(int(t) for t in np.flatnonzero(self._eog))  # llama.cpp's end-of-generation
        self._full = np.zeros(self.n_vocab, dtype=[("id", np.intc), ("logit", np.single), ("p", np.single)])
        self._few = np.zeros(_TOP, dtype=self._full.dtype)
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
        return continuation_tokens(text, self.tokenize, self._piece)

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

    def _sync(self, context: Sequence[int]) -> None:
        """Make the cache hold ``context`` and the logits be those of its last token."""
        context = list(context)
        if len(context) >= self.n_ctx:
            raise ModelError(f"the context ({len(context)} tokens) does not fit n_ctx={self.n_ctx}")
        common = shared_prefix(self._tokens, context)
        if common == len(context) == len(self._tokens) and self._fresh:
            return
        # Re-evaluate at least one token for its logits, and no part of a batch alone.
        self._truncate(keep_whole(self._alone, min(common, len(context) - 1)))
        self._evaluate(context[len(self._tokens):])

    def _truncate(self, size: int) -> None:
        """Keep the first ``size`` tokens of the cache; the logits are stale until the next evaluation."""
        self.llm.n_tokens = size
        if size == 0:  # as new: a cache whose cells are laid out afresh computes as a new context does
            self._lib.llama_memory_clear(self._lib.llama_get_memory(self._ctx), True)
        else:
            self.llm._ctx.kv_cache_seq_rm(-1, size, -1)
        self._tokens, self._alone = self._tokens[:size], self._alone[:size]
        self._fresh = False

    # -------------------------------------------------------------- prefixes

    def _store_key(self, prefix: Sequence[int]) -> str:
        from ...provenance import sha256_file

        return state_key({**self._settings, "model": sha256_file(self.model)}, prefix)

    def _state_bytes(self) -> int:
        return int(self._lib.llama_state_seq_get_size(self._ctx, 0))

    def _snapshot(self) -> bytes:
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
        self.llm.input_ids[: len(prefix)] = prefix
        self.llm.n_tokens = len(prefix)
        self._tokens, self._alone = list(prefix), [False] * len(prefix)  # evaluated in batches
        return True

    def _state_size(self, state: bytes) -> int:
        return len(state)

    def _evaluate(self, tokens: list[int]) -> None:
        if not tokens:
            return
        self.llm.eval(tokens)
        self._lib.llama_synchronize(self._ctx)  # on a GPU evaluation runs on after eval returns
        self.evaluated_tokens += len(tokens)
        self._tokens.extend(tokens)
        self._alone.extend([len(tokens) == 1] * len(tokens))
        self._fresh = True

    def engine_seconds(self, tokens: Sequence[int], n_batch: int = GPU_BATCH) -> float:
        """Seconds llama.cpp alone takes to evaluate ``tokens`` from an empty cache: a context of its own on the
        same weights with this backend's settings (threads, attention) but llama.cpp's default batches, the last
        token's logits only, after a warm-up. What ``bench`` measures :meth:`prefill` against."""
        lib = self._lib
        if not tokens:
            return 0.0
        mine = self.llm.context_params
        params = type(mine).from_buffer_copy(mine)
        params.n_ctx = min(self.n_ctx, -(-(len(tokens) + 8) // 256) * 256)
        params.n_batch, params.n_ubatch = n_batch, UBATCH
        ctx = lib.llama_init_from_model(self.llm._model.model, params)
        if not ctx:
            raise ModelError("llama.cpp could not make a second context for the engine's own timing")
        batch = lib.llama_batch_init(n_batch, 0, 1)
        try:
            def run(chunk: Sequence[int], start: int, last: bool) -> None:
                batch.n_tokens = len(chunk)
                for i, token in enumerate(chunk):
                    batch.token[i], batch.pos[i], batch.n_seq_id[i] = token, start + i, 1
                    batch.seq_id[i][0], batch.logits[i] = 0, last and i == len(chunk) - 1
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

    def _logits(self) -> np.ndarray:
        ptr = self._lib.llama_get_logits_ith(self._ctx, -1)
        return np.ctypeslib.as_array(ptr, shape=(self.n_vocab,)).copy()

    # -------------------------------------------------------------- grammars

    def _grammar_sampler(self, grammar: Grammar):
        sampler = self._lib.llama_sampler_init_grammar(self._vocab, grammar.to_gbnf().encode(), b"root")
        if not sampler:
            raise GrammarError("llama.cpp rejected a grammar:\n" + grammar.to_gbnf())
        return sampler

    def _apply(self, sampler, buffer: np.ndarray, count: int) -> None:
        array = self._lib.llama_token_data_array(
            data=buffer.ctypes.data_as(self._lib.llama_token_data_p), size=count, selected=-1, sorted=False
        )
        self._lib.llama_sampler_apply(sampler, ctypes.byref(array))

    def _allowed(self, sampler, token: int) -> bool:
        self._few[0] = (token, 0.0, 0.0)
        self._apply(sampler, self._few, 1)
        return bool(np.isfinite(self._few["logit"][0]))

    def _masked(self, sampler, logits: np.ndarray) -> np.ndarray:
        self._full["id"] = np.arange(self.n_vocab, dtype=np.intc)
        self._full["logit"] = logits
        self._apply(sampler, self._full, self.n_vocab)
        masked = np.full(self.n_vocab, -np.inf, dtype=np.float32)
        masked[self._full["id"]] = self._full["logit"]
        if self._ends:  # the end of sequence is the model's to choose (see END_RANK)
            for end in self.end_tokens:
                if may_end(logits, end):
                    masked[end] = logits[end]
        return masked

    def _pick(self, logits: np.ndarray, sampler, sampling: Sampling, rng: np.random.Generator,
              avoid: Callable[[int], bool] | None = None) -> int:
        """The next token, greedy or sampled, among those the grammar admits and, where any of them is
        left, those ``avoid`` does not refuse. The end of sequence is always admitted: where the model
        ends, the planner completes the output (see :mod:`..decoding.writer`)."""
        if not np.isfinite(logits[int(np.argmax(logits))]):
            raise ModelError("the model's scores are not numbers (NaN or infinite logits): its weights, or the build "
                             "that runs them, are broken (on a GPU, see whether --n-gpu-layers 0 runs it)")
        if sampling.temperature <= 0:
            best = int(np.argmax(logits))
            if (self._admits(sampler, best)) and not (avoid and avoid(best)):
                return best
            top = np.argpartition(-logits, _TOP)[:_TOP]
            top = top[np.argsort(-logits[top], kind="stable")]
            self._few["id"] = top
            self._few["logit"] = logits[top]
            if sampler is not None:
                self._apply(sampler, self._few, _TOP)
                if self._ends:
                    self._few["logit"][self._eog[top]] = logits[top][self._eog[top]]
            admitted = self._few["id"][np.isfinite(self._few["logit"])]
            if not len(admitted) or (avoid and len(admitted) < TRIES and all(avoid(int(t)) for t in admitted)):
                masked = self._masked(sampler, logits)
                if not np.isfinite(masked).any():
                    raise GrammarError("the grammar admits no token here")
                admitted = np.argsort(-masked, kind="stable")[: int(np.isfinite(masked).sum())]
            # The best admitted token that ``avoid`` does not refuse, among the best TRIES; else the best.
            return next((int(t) for t in admitted[:TRIES] if not (avoid and avoid(int(t)))), int(admitted[0]))
        scaled = logits.astype(np.float64) / sampling.temperature
        probs = np.exp(scaled - scaled.max())
        probs /= probs.sum()
        token = int(rng.choice(self.n_vocab, p=probs))
        if self._admits(sampler, token) and not (avoid and avoid(token)):
            return token
        masked = self._masked(sampler, logits).astype(np.float64) / sampling.temperature if sampler else scaled
        if not np.isfinite(masked).any():
            raise GrammarError("the grammar admits no token here")
        return draw(np.exp(masked - masked[np.isfinite(masked)].max()), rng, avoid, TRIES)

    def _admits(self, sampler, token: int) -> bool:
        return sampler is None or (self._ends and bool(self._eog[token])) or self._allowed(sampler, token)

    # ------------------------------------------------------------ generation

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
        rng = rng or np.random.default_rng(sampling.seed)
        if len(context) + max_tokens > self.n_ctx:
            max_tokens = self.n_ctx - len(context) - 1
        self._sync(context)
        self._ends = sampling.aligned
        sampler = self._grammar_sampler(grammar) if grammar is not None else None
        matcher = Matcher(grammar) if grammar is not None else None
        guard = sampling.loop_guard
        out = Generated([], "", "length")
        decoder = codecs.getincrementaldecoder("utf-8")("replace")
        try:
            while len(out.tokens) < max_tokens:
                new = self._forced_tokens(matcher.forced(), sampler, heal=sampling.aligned) if matcher else []
                forced = len(new)
                if not new:
                    logits = self._logits()
                    token = self._pick(logits, sampler, sampling, rng)
                    line = current_line(out.text)
                    if guard is not None and guard.loops(line + self._text(token)):
                        # A loop: end the free text it runs in (the grammar's shortest way on), or else
                        # take the best token that does not close the loop.
                        new = self._forced_tokens(matcher.shortest_way(), sampler, way=True) if matcher else []
                        forced = len(new)
                        token = token if new else self._pick(
                            logits, sampler, sampling, rng, lambda t: guard.loops(line + self._text(t)))
                        out.loops += 1
                    if not new:
                        self._measure(out, logits, token, sampler)
                if not new:
                    if self._eog[token]:
                        out.text += decoder.decode(b"", final=True)
                        out.stop = "eos"
                        return out
                    if sampler is not None:
                        self._lib.llama_sampler_accept(sampler, token)
                    new = [token]
                out.tokens.extend(new)
                out.forced += forced
                self._evaluate(new)
                piece = decoder.decode(b"".join(self._piece(t) for t in new))
                if matcher is not None and not matcher.advance(piece):
                    raise GrammarMismatchError(out.text + piece, "llama.cpp's grammar let the model write it, "
                                               "the planner's grammar does not allow it")
                out.text += piece
                if sampler is not None and out.text.count("\n") >= lines:
                    out.stop = "line"
                    return out
                for s in stop:
                    if s in out.text:
                        out.text, out.stop = out.text[: out.text.index(s)], "stop"
                        return out
            out.text += decoder.decode(b"", final=True)
            return out
        finally:
            if sampler is not None:
                self._lib.llama_sampler_free(sampler)

    def _measure(self, out: Generated, logits: np.ndarray, token: int, sampler) -> None:
        """How far the grammar bent the model at a token it chose: whether its likeliest token was refused,
        and the chosen token's log-probability under the unconstrained model."""
        best = int(np.argmax(logits))
        out.choices += 1
        out.refused += best != token and not self._admits(sampler, best)
        top = float(logits[best])
        out.logprob += float(logits[token]) - top - float(np.log(np.exp(logits - top, dtype=np.float64).sum()))

    def _forced_tokens(self, forced: str, sampler, *, way: bool = False, heal: bool = True) -> list[int]:
        """The tokens of text the planner's grammar forces, all in one batch, accepted by llama.cpp's grammar;
        with ``heal``, all but the last, which the model writes itself (it may run on into what follows: token
        healing). A loop guard's ``way`` out is written whole.

        Each is checked before llama.cpp accepts it: accepting a token its grammar refuses aborts the process.
        """
        if len(forced) < 2 and not way:  # one character costs no more sampled than forced
            return []
        tokens = self.tokenize_continuation(forced)
        if heal and not way:
            tokens = tokens[:-1]
        for token in tokens:
            if not self._allowed(sampler, token):
                raise GrammarMismatchError(forced, "the planner's grammar forces it, llama.cpp's grammar refuses it")
            self._lib.llama_sampler_accept(sampler, token)
        return tokens

    def _text(self, token: int) -> str:
        return self._piece(token).decode("utf-8", errors="replace")

    def close(self) -> None:
        llm, self.llm = getattr(self, "llm", None), None
        if llm is not None:
            llm.close()
