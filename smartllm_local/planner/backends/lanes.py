"""Lanes: several sequences of one model decoded together, their tokens evaluated in shared batches.

A stage's candidates (one prompt, each its own sampling) and the stages of tasks planned at once are sequences
that need not wait for one another. Evaluating a token of each of n sequences in one call costs little more than
one token alone where the device has room to spare (a GPU: the weights are read once for all n), so n sequences
written together take about the time of one.

:func:`open_lanes` gives n views of any backend: a backend with a method ``lanes(n)`` provides them, any other
runs the n sequences one after another through itself. The llama.cpp backend's lanes (:class:`LaneEngine`):

- a second llama.cpp context on the model's weights holds the n sequences, each in key/value cells of its own
  (n_ctx each: a sequence's cells lie as they would in the backend's own cache, so that where the model's logits do
  not change with batching, SmolLM2's, a greedy lane writes exactly what the backend writes alone; Qwen2.5-Coder's
  do: a shorter lane batched with a longer one attends over as many cells as the longer, which moves its logits);
  or, with ``unified``, all in one cache of n_ctx cells, where a prefix they share is held once but their cells
  interleave, and the order in which llama.cpp sums over them moves logits in their last bits (measured: on kitchen-01's
  decomposition SmolLM2 wrote `Put` where it writes `put` alone);
- each view (:class:`LaneView`) is a whole backend, its ``generate`` the backend's own decoding loop
  (:mod:`..decoding.loop`: the same token choice, loop guard, end of sequence and grammar cross-check), driven
  from a thread of its own; only evaluating tokens differs: it is a request to the engine, made when the loop
  asks for logits, carrying the drafts the backend's own batch would carry (:mod:`.drafts`), so that a lane's
  pieces are the backend's;
- the engine's thread evaluates, in ONE ``llama_decode``, what every lane that is inside a call (generate,
  prefill) has asked for, as soon as each of them has asked. A lane between calls (the stage code between
  lines, a world check) holds no one up, and one that returns or raises is no longer waited for: continuous
  batching, as llama-server's slots. A lane's single token and another's forced tokens or prompt go in the same
  batch, single tokens first;
- a context that shares a prefix with what another lane's sequence holds gets those cells copied
  (``llama_memory_seq_cp``: a copy of the other's cells, or in a unified cache the same cells), and one that
  shares more with a prompt
  another lane is evaluating now waits for it: a prompt n lanes are given at once is evaluated once;
- a prompt whose shared prefix (a stage's examples, a scene) has a state kept by the backend
  (:class:`.PrefixReuse`, in memory or its store) starts from that state, loaded into the lane's sequence
  (``llama_state_seq_set_data``), where no lane's sequence holds as much. Lanes keep no state of their own: a
  prefix the backend has not kept is evaluated in the lanes' context (once) and forgotten with it.
"""

from __future__ import annotations

import contextlib
import ctypes
import struct
import threading
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...errors import ModelError
from ..decoding.first_bytes import FirstBytes
from ..decoding.grammar import Grammar
from ..decoding.sampling import Generated, Sampling
from .base import Backend, shared_prefix
from .drafts import draft_size, lookup
from .llamacpp_decoding import LlamaDecoding, fill_batch

_ONE_STREAM = struct.pack("<I", 1)  # the stream count of a state from a cache of one stream of cells


@contextlib.contextmanager
def open_lanes(backend: Backend, n: int) -> Iterator[tuple[list[Backend], bool]]:
    """n views of ``backend`` for n sequences written at once; the bool says whether the views may be (and should be)
    driven concurrently, one thread each. A backend with a method ``lanes(n)`` (a context manager yielding the views)
    provides them; any other backend gets ([backend] * n, False) and the caller runs the n sequences one after another.
    """
    if n < 1:
        raise ValueError(f"lanes: n must be 1 or more, not {n}")
    lanes = getattr(backend, "lanes", None)
    if n == 1 or lanes is None:
        yield [backend] * n, False
        return
    with lanes(n) as views:
        yield views, True


@dataclass(eq=False)
class _Lane:
    """One sequence: what its cells hold, and the request its thread waits on (written by the engine's thread while
    that thread waits)."""

    seq: int
    tokens: list[int] = field(default_factory=list)  # the context its sequence holds
    rows: np.ndarray | None = None  # the logits after its last token, then after each of ``ahead``
    ahead: list[int] = field(default_factory=list)  # drafts its sequence holds after the context
    evaluated: int = 0
    target: list[int] | None = None  # a context the sequence is to hold (else the request extends it)
    state: tuple[list[int], bytes] | None = None  # a prefix of the target and its state, kept by the backend
    todo: list[int] | None = None  # of the request, the tokens still to evaluate (None: not started), drafts last
    real: int = 0  # of those, how many are the context's (the rest are drafts)
    drafts: bool = False  # whether the request is to carry drafts (see .drafts)
    trim: bool = False  # whether drafts left in its sequence are to be taken out before the request's tokens
    done: bool = True
    error: str = ""

    def draft(self, context: Sequence[int], todo: list[int], room: int) -> None:
        """Set the request's tokens: ``todo`` (the last of ``context``), and drafts after them where it carries
        any (at most ``room``)."""
        self.ahead = lookup(context, min(draft_size(len(todo)), room)) if self.drafts else []
        self.todo, self.real = todo + self.ahead, len(todo)


class LaneEngine:
    """n sequences of a :class:`.LlamaCppBackend`'s model in a context of their own, evaluated in shared batches by a
    thread of the engine's (see the module's docstring)."""

    def __init__(self, parent: Any, n: int, n_ctx: int, unified: bool = False):
        if n < 1:
            raise ValueError(f"lanes: n must be 1 or more, not {n}")
        self._lib = lib = parent._lib
        self.n_vocab, self.n_ctx = parent.n_vocab, parent.n_ctx  # a lane's drafts fit as the backend's do
        self.unified = unified
        self._streams = 1 if unified else n
        self.ctx = parent._new_context("lanes", n_ctx=n_ctx * self._streams, n_seq_max=n, kv_unified=unified)
        self.n_batch = int(lib.llama_n_batch(self.ctx))
        self._batch = lib.llama_batch_init(self.n_batch, 0, 1)
        self._memory = lib.llama_get_memory(self.ctx)
        self.evaluated_tokens = 0  # all lanes together
        self.decodes = 0  # llama_decode calls
        self._lanes = [_Lane(seq) for seq in range(n)]
        self._cond = threading.Condition()
        self._pending: list[_Lane] = []
        self._inside = 0  # lanes inside a call (generate, prefill): the ones a batch waits for
        self._closed = False
        self.tokenizing = threading.Lock()
        self.views = [LaneView(self, lane, parent) for lane in self._lanes]
        self._thread = threading.Thread(target=self._serve, name="llama.cpp lanes", daemon=True)
        self._thread.start()

    # ------------------------------------------------------------ lanes' side

    @contextlib.contextmanager
    def inside(self) -> Iterator[None]:
        """A lane's call: while it lasts, a batch waits for the lane's request; after it, no longer."""
        with self._cond:
            self._inside += 1
        try:
            yield
        finally:
            with self._cond:
                self._inside -= 1
                self._cond.notify_all()

    def ask(self, lane: _Lane, tokens: list[int], *, extend: bool, drafts: bool,
            state: tuple[list[int], bytes] | None = None) -> None:
        """Make ``lane``'s sequence hold ``tokens`` (or hold them after what it holds: ``extend``), with the logits
        of the last, and ``drafts`` after them as the backend would evaluate them (see :mod:`.drafts`); returns once
        a batch has evaluated them. ``state``: a prefix of ``tokens`` and its kept state, loaded where no sequence
        holds as much."""
        with self._cond:
            if self._closed:
                raise ModelError("the lanes were closed: a lane was used after its lanes' context ended")
            lane.drafts, lane.state, lane.rows = drafts, state, None
            if extend:
                lane.target, lane.trim = None, True
                lane.draft(lane.tokens + tokens, list(tokens), self.n_ctx - 1 - len(lane.tokens) - len(tokens))
            else:
                lane.target, lane.todo = list(tokens), None
            lane.done, lane.error = False, ""
            self._pending.append(lane)
            self._cond.notify_all()
            while not lane.done:
                self._cond.wait()
            if lane.error:
                raise ModelError(lane.error)

    # ------------------------------------------------------------ engine's side

    def _serve(self) -> None:
        """Evaluate a batch whenever every lane inside a call has a request waiting, until closed."""
        while True:
            with self._cond:
                while not self._closed and not (self._pending and len(self._pending) >= self._inside):
                    self._cond.wait()
                if self._closed:
                    self._fail(list(self._pending), "the lanes were closed while a lane waited for a batch")
                    return
                waiting = list(self._pending)
            try:
                finished = self._step(waiting)
            except Exception as exc:  # noqa: BLE001 - every waiting lane must hear of it, never hang
                with self._cond:
                    self._fail(waiting, str(exc) if isinstance(exc, ModelError) else f"the lanes failed: {exc!r}")
                continue
            with self._cond:
                for lane in finished:
                    lane.done = True
                    self._pending.remove(lane)
                self._cond.notify_all()

    def accept(self, lane: _Lane, tokens: list[int]) -> None:
        """Make drafts ``lane``'s sequence holds the context's (under the lock: another lane's request may be reading
        what this one's sequence holds, to copy it)."""
        with self._cond:
            lane.tokens.extend(tokens)
            lane.ahead = lane.ahead[len(tokens):]
            lane.evaluated += len(tokens)

    def _fail(self, lanes: list[_Lane], why: str) -> None:
        """Fail requests (called with the lock held): their sequences are emptied, their threads raise ``why``."""
        for lane in lanes:
            self._lib.llama_memory_seq_rm(self._memory, lane.seq, -1, -1)
            lane.tokens, lane.rows, lane.ahead, lane.target, lane.todo, lane.state = [], None, [], None, None, None
            lane.error, lane.done = why, True
            if lane in self._pending:
                self._pending.remove(lane)
        self._cond.notify_all()

    def _step(self, waiting: list[_Lane]) -> list[_Lane]:
        """One batch, as much as fits; the lanes whose requests it completed. In a unified cache: single tokens
        first, then forced tokens and prompts. With a stream of cells per lane, llama.cpp would split a batch into
        pieces of as many tokens from each lane, evaluating a piece of a lane's tokens otherwise than the backend
        alone does (a lone token computes otherwise): so a batch holds the first lane to have asked and those whose
        next piece is as long, and each lane's pieces are those the backend would evaluate."""
        room, chunks, size = self.n_batch, [], None
        order = sorted(waiting, key=lambda ln: (ln.todo is None, len(ln.todo or ()) > 1, ln.seq)) if self.unified \
            else waiting  # in the order they asked
        for lane in order:
            if room == 0:
                break
            if lane.todo is None and not self._start(lane, waiting):
                continue
            if self.unified and len(lane.todo) > room >= lane.real:  # drafts go in the batch of the context's end
                lane.todo, lane.ahead = lane.todo[:lane.real], []
            chunk = lane.todo[:room] if self.unified else lane.todo[:self.n_batch]
            if not self.unified and (len(chunk) > room or size not in (None, len(chunk))):
                continue
            if lane.trim:  # the drafts of its last request, where the model chose otherwise
                self._lib.llama_memory_seq_rm(self._memory, lane.seq, len(lane.tokens), -1)
                lane.trim = False
            size = len(chunk)
            chunks.append((lane, chunk))
            room -= len(chunk)
        if not chunks:  # cannot be: the first request started is never held back (and a request is never empty)
            raise ModelError("the lanes' requests wait on one another")
        outputs = self._decode(chunks)
        finished = []
        for lane, chunk in chunks:
            context = min(len(chunk), lane.real)
            lane.tokens.extend(chunk[:context])
            lane.todo, lane.real = lane.todo[len(chunk):], lane.real - context
            lane.evaluated += context
            lane.rows = outputs.get(lane.seq)
            if not lane.todo:
                lane.target = lane.todo = None
                finished.append(lane)
        return finished

    def _start(self, lane: _Lane, waiting: list[_Lane]) -> bool:
        """Begin a request for a whole context: keep what the lane's sequence shares with it, or copy a longer
        shared prefix from another lane's, or load a longer one's state the request brought; the rest (at least
        the last token, for its logits) is to evaluate. False (it waits) where a prompt another lane is
        evaluating now shares more with it."""
        target = lane.target
        limit = len(target) - 1
        source, kept = lane, min(shared_prefix(lane.tokens, target), limit)
        for other in self._lanes:
            shared = min(shared_prefix(other.tokens, target), limit) if other is not lane else 0
            if shared > kept:
                source, kept = other, shared
        state = lane.state if lane.state is not None and kept < len(lane.state[0]) <= limit else None
        reach = len(state[0]) if state is not None else kept
        for other in waiting:
            if other is not lane and other.target is not None and other.todo:
                if min(shared_prefix(other.target, target), limit) > reach:
                    return False
        lib = self._lib
        if state is not None:
            source, kept = lane, len(state[0]) if self._load(lane, state[1]) else 0
        if source is lane:
            lib.llama_memory_seq_rm(self._memory, lane.seq, kept, -1)
        elif self.unified:
            lib.llama_memory_seq_rm(self._memory, lane.seq, -1, -1)
            lib.llama_memory_seq_cp(self._memory, source.seq, lane.seq, 0, kept)
        else:  # a sequence of its own cells: llama.cpp copies another's whole
            lib.llama_memory_seq_rm(self._memory, lane.seq, -1, -1)
            lib.llama_memory_seq_cp(self._memory, source.seq, lane.seq, -1, -1)
            lib.llama_memory_seq_rm(self._memory, lane.seq, kept, -1)
        lane.tokens, lane.state = target[:kept], None
        lane.draft(target, target[kept:], self.n_ctx - 1 - len(target))
        return True

    def _load(self, lane: _Lane, state: bytes) -> bool:
        """Load a state kept by the backend into the lane's sequence, in place of what it held; False (the sequence
        left empty) where llama.cpp refuses it (no room for its cells in one piece)."""
        lib = self._lib
        for blob in self._blobs(state):
            lib.llama_memory_seq_rm(self._memory, lane.seq, -1, -1)
            source = ctypes.cast(blob, ctypes.POINTER(ctypes.c_uint8))  # read in place, not copied
            if lib.llama_state_seq_set_data(self.ctx, source, len(blob), lane.seq):
                return True
        lib.llama_memory_seq_rm(self._memory, lane.seq, -1, -1)
        return False

    def _blobs(self, state: bytes) -> Iterator[bytes]:
        """A state kept by the backend, as it is; and, in a cache of a stream of cells per sequence, as such a cache
        reads one: the backend's says one stream (after llama.cpp 0.3.36's 8-byte header), and llama.cpp reads a
        sequence's state only where it says as many, so the others are said to be empty (every stream's cells of
        a sequence's state go into that sequence's own)."""
        yield state
        if self._streams > 1 and state[8:12] == _ONE_STREAM:
            yield state[:8] + struct.pack("<I", self._streams) + state[12:] + bytes(4 * (self._streams - 1))

    def _decode(self, chunks: list[tuple[_Lane, list[int]]]) -> dict[int, np.ndarray]:
        """Evaluate the chunks in one call; for each lane whose chunk ends its request, by sequence, the logits after
        the context's last token and after each draft."""
        lib, batch = self._lib, self._batch
        at, wanted = 0, {}
        for lane, chunk in chunks:
            ends = len(chunk) == len(lane.todo)
            at = fill_batch(batch, chunk, len(lane.tokens), seq=lane.seq,
                            logits_from=lane.real - 1 if ends else len(chunk), at=at)
            if ends:
                wanted[lane.seq] = range(at - len(chunk) + lane.real - 1, at)
        batch.n_tokens = at
        status = lib.llama_decode(self.ctx, batch)
        if status != 0:
            held = sum(len(lane.tokens) for lane in self._lanes)
            raise ModelError(f"llama.cpp could not evaluate the lanes' batch (status {status}"
                             + (f": their key/value cache is full, {held} tokens in the lanes' sequences; give the "
                                "lanes more cells (n_ctx) or use fewer lanes)" if status == 1 else ")"))
        lib.llama_synchronize(self.ctx)
        self.evaluated_tokens += at
        self.decodes += 1
        return {seq: np.stack([np.ctypeslib.as_array(lib.llama_get_logits_ith(self.ctx, i), shape=(self.n_vocab,))
                               for i in rows]) for seq, rows in wanted.items()}

    def close(self) -> None:
        """Stop the engine's thread (a lane still waiting raises) and free the lanes' context."""
        with self._cond:
            self._closed = True
            self._cond.notify_all()
        self._thread.join()
        self._lib.llama_batch_free(self._batch)
        self._lib.llama_free(self.ctx)


class LaneView(LlamaDecoding):
    """One lane as a whole backend: the parent's tokenizer and model, a sequence of its own in the lanes' context,
    the backend's decoding loop (its own grammar sampler, buffers and end-of-sequence setting). Drive each view
    from one thread."""

    def __init__(self, engine: LaneEngine, lane: _Lane, parent: Any):
        self._engine, self._lane, self._parent = engine, lane, parent
        self.name, self.model, self.n_ctx = parent.name, parent.model, parent.n_ctx
        self.chat_template, self.bos_token, self.eos_token = parent.chat_template, parent.bos_token, parent.eos_token
        self.trained_context, self.n_gpu_layers = parent.trained_context, parent.n_gpu_layers
        self._lib, self._vocab, self.n_vocab = parent._lib, parent._vocab, parent.n_vocab
        self._init_decoding(parent.end_tokens, parent._drafting)  # lanes evaluate as their backend does

    @property
    def evaluated_tokens(self) -> int:
        """Tokens this lane's sequence had evaluated (a prefix copied from another lane's is not counted)."""
        return self._lane.evaluated

    @property
    def batches(self) -> int:
        """``llama_decode`` calls the lanes have made, all together."""
        return self._engine.decodes

    # the parent's tokenizer, one thread at a time
    def tokenize(self, text: str, *, bos: bool = False, special: bool = False) -> list[int]:
        with self._engine.tokenizing:
            return self._parent.tokenize(text, bos=bos, special=special)

    def detokenize(self, tokens: Sequence[int]) -> str:
        return self._parent.detokenize(tokens)

    def tokenize_continuation(self, text: str) -> list[int]:
        with self._engine.tokenizing:
            return self._parent.tokenize_continuation(text)

    def text_of(self, tokens: Sequence[int]) -> str:
        return self._parent.text_of(tokens)

    def adds_bos(self) -> bool:
        return self._parent.adds_bos()

    def _piece(self, token: int, special: bool = False) -> bytes:
        return self._parent._piece(token, special)

    def first_bytes(self) -> FirstBytes:
        return self._parent.first_bytes()

    # a sequence of the lanes' context
    def prefill(self, context: Sequence[int], prefixes: Sequence[int]) -> int:
        """Make the lane's sequence hold ``context``: from what a lane's sequence shares with it, or else from the
        longest prefix whose state the backend keeps (loaded, never stored); returns how many of its tokens were
        not evaluated now."""
        with self._engine.inside():
            before = self._lane.evaluated
            kept = self._parent.kept_state(context, prefixes) if prefixes else None
            self.sync(context, kept)
            self._settle(drafts=True)
            return len(context) - (self._lane.evaluated - before)

    def generate(self, context: Sequence[int], *, grammar: Grammar | None, max_tokens: int, sampling: Sampling,
                 stop: Sequence[str] = (), rng: np.random.Generator | None = None, lines: int = 1) -> Generated:
        with self._engine.inside():
            return super().generate(context, grammar=grammar, max_tokens=max_tokens, sampling=sampling, stop=stop,
                                    rng=rng, lines=lines)

    def sync(self, context: Sequence[int], state: tuple[list[int], bytes] | None = None) -> None:
        """As the backend's: a context that goes on from the lane's is evaluated after it when logits are next asked
        for; another, or one with a kept ``state`` to start from, is a request for a whole context now (see
        :meth:`LaneEngine._start`)."""
        if not context:
            raise ModelError("a lane was given an empty context: there is no token to go on from")
        if state is None:
            super().sync(context)
        else:
            self._ask_whole(self._fitted(context), state)

    def _restart(self, context: list[int], common: int) -> None:
        self._ask_whole(context, None)

    def _ask_whole(self, context: list[int], state: tuple[list[int], bytes] | None) -> None:
        self._pending = []
        self._engine.ask(self._lane, context, extend=False, drafts=self._drafting, state=state)
        self._rows = self._lane.rows

    def _held(self) -> list[int]:
        return self._lane.tokens

    def _drafts(self) -> list[int]:
        return self._lane.ahead

    def _keep_drafts(self, count: int) -> None:
        self._engine.accept(self._lane, self._lane.ahead[:count])

    def _drop_drafts(self) -> None:
        self._lane.ahead = []  # out of its cells before its next request (see LaneEngine._step)

    def _flush(self, drafts: bool) -> None:
        pending, self._pending = self._pending, []
        self._engine.ask(self._lane, pending, extend=True, drafts=drafts)
        self._rows = self._lane.rows

    def close(self) -> None:
        """Nothing: the lanes' context is freed when the lanes end."""
