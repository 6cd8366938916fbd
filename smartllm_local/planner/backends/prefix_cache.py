"""Prompt prefixes evaluated once: their key/value state kept in memory and on disk.

Every prompt of a stage begins with the same examples (see prompts.py), so the
model's key/value state after them is the same for every task; a decomposition
then lists its scene's objects, the same for every task on that floor plan. A
backend keeps the states it made in memory (bounded in bytes) for the rest of
the process, and a :class:`PrefixStore` keeps them on disk for the next process:
a second ``plan`` call on the same model starts from the examples' state, and
on the same floor plan from the scene's.

An entry is keyed by everything the state depends on (the model file's digest,
the backend and its settings, the prefix's tokens) and holds those tokens and
the digest of its state, so a corrupt, truncated or colliding entry is never
trusted: it is deleted and the prefix is evaluated again. The store is bounded
in bytes: the least recently used entries go first.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from collections import OrderedDict
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from ...errors import ModelError, UserError
from ...files import check_output_folder, write_atomic

_MAGIC = b"smartllm-local prefix state 1\n"
_SUFFIX = ".kv"
DEFAULT_STORE_BYTES = 4 << 30  # a 70B model's examples take about 1 GB each stage
DEFAULT_MEMORY_BYTES = 2 << 30


def default_store_folder() -> Path:
    from ...world.scenes import cache_root

    return cache_root() / "prefix-states"


def open_store(setting: str | Path | None) -> PrefixStore | None:
    """The store ``--prefix-cache`` names: a folder, ``off`` (none), or None for the user's cache."""
    if setting is not None and str(setting) == "off":
        return None
    folder = Path(setting).expanduser() if setting is not None else default_store_folder()
    return PrefixStore(check_output_folder(folder, "--prefix-cache"))


def state_key(identity: Mapping[str, Any], prefix: Sequence[int]) -> str:
    """The digest naming a prefix's state for a model as ``identity`` describes it."""
    hasher = hashlib.sha256(json.dumps(identity, sort_keys=True).encode())
    hasher.update(b"\0" + b",".join(str(t).encode() for t in prefix))
    return hasher.hexdigest()


class PrefixStore:
    """Prefix states on disk, one file per entry, at most ``max_bytes`` in all."""

    def __init__(self, folder: Path, max_bytes: int = DEFAULT_STORE_BYTES):
        self.folder = Path(folder)
        self.max_bytes = max_bytes
        self.rejected = 0  # entries found corrupt and deleted

    def _path(self, key: str) -> Path:
        return self.folder / f"{key}{_SUFFIX}"

    def load(self, key: str, prefix: Sequence[int]) -> bytes | None:
        """The state stored for ``prefix`` under ``key``; None when there is none or it cannot be trusted."""
        path = self._path(key)
        try:
            data = path.read_bytes()
        except OSError:
            return None
        state = _unpack(data, prefix)
        if state is None:
            self.rejected += 1
            _unlink(path)
            return None
        self.touch(key)
        return state

    def has_entries(self) -> bool:
        """Whether any state is stored: until one is, nothing needs the model's digest (a 70B file takes half a
        minute to digest the first time)."""
        return next(self.folder.glob(f"*{_SUFFIX}"), None) is not None

    def touch(self, key: str) -> None:
        """Mark an entry recently used: evicted last."""
        try:
            os.utime(self._path(key))
        except OSError:
            pass

    def save(self, key: str, prefix: Sequence[int], state: bytes) -> bool:
        """Store a state (atomically: a reader sees all of it or nothing), then keep the store in its
        bound. A store that cannot be written only costs the next process the prefix: False."""
        header = json.dumps({"tokens": list(prefix), "size": len(state),
                             "sha256": hashlib.sha256(state).hexdigest()}).encode()
        try:
            write_atomic(self._path(key), [_MAGIC, header, b"\n", state])
        except (UserError, OSError):
            return False
        self.evict()
        return True

    def evict(self) -> None:
        """Delete the least recently used entries until the rest fit ``max_bytes``."""
        entries = []
        for path in self.folder.glob(f"*{_SUFFIX}"):
            try:
                stat = path.stat()
            except OSError:
                continue
            entries.append((stat.st_mtime_ns, stat.st_size, path))
        total = sum(size for _, size, _ in entries)
        for _, size, path in sorted(entries):
            if total <= self.max_bytes:
                break
            _unlink(path)
            total -= size


def _unpack(data: bytes, prefix: Sequence[int]) -> bytes | None:
    if not data.startswith(_MAGIC):
        return None
    end = data.find(b"\n", len(_MAGIC))
    if end < 0:
        return None
    try:
        header = json.loads(data[len(_MAGIC):end])
    except ValueError:
        return None
    state = data[end + 1:]
    if (not isinstance(header, dict) or header.get("tokens") != list(prefix) or header.get("size") != len(state)
            or header.get("sha256") != hashlib.sha256(state).hexdigest()):
        return None
    return state


def _unlink(path: Path) -> None:
    try:
        path.unlink()
    except OSError:
        pass


class MemoryStates:
    """Prefix states kept by a backend for the rest of the process, least recently used dropped first
    beyond ``max_bytes``."""

    def __init__(self, max_bytes: int = DEFAULT_MEMORY_BYTES):
        self.max_bytes = max_bytes
        self._states: OrderedDict[tuple[int, ...], tuple[Any, int]] = OrderedDict()

    def get(self, prefix: Sequence[int]) -> Any | None:
        key = tuple(prefix)
        found = self._states.get(key)
        if found is None:
            return None
        self._states.move_to_end(key)
        return found[0]

    def touch(self, prefix: Sequence[int]) -> None:
        if tuple(prefix) in self._states:
            self._states.move_to_end(tuple(prefix))

    def put(self, prefix: Sequence[int], state: Any, size: int) -> None:
        self._states[tuple(prefix)] = (state, size)
        self._states.move_to_end(tuple(prefix))
        while sum(s for _, s in self._states.values()) > self.max_bytes and len(self._states) > 1:
            self._states.popitem(last=False)


class PrefixReuse:
    """What both backends do with a prompt's shared prefixes (mixed into each). A backend provides
    ``_states`` (a :class:`MemoryStates`), ``prefix_store`` (None for none), and the hooks below.

    Each part after a prefix is always evaluated on a state loaded back from its snapshot, also right
    after the prefix was first evaluated: with a sliding-window model (Gemma-3) a loaded state does
    not give quite the logits of the live cache it was taken from, so loading it every time is what
    makes a task's output the same whichever way the state came (evaluated now, kept, or stored).

    Keeping a state costs copying it out of the engine and back (and, for the store, hashing it and
    writing it to disk): on a CPU that is a small share of evaluating the prefix, so a backend on the CPU
    always keeps them (``keeps_states`` set from the start); on a GPU it can cost more than evaluating it
    again, so there the first prefix a backend evaluates (of at least ``_DECIDE_TOKENS``) decides, from
    its measured evaluation time and its state's size per token, whether keeping states pays (costs at
    most ``KEEP_SHARE`` of evaluating them), in memory and in the store; where it does not, prompts are
    evaluated whole, at the engine's speed, on whatever prefix the live cache shares with them."""

    # What keeping a state costs, per byte of it: copied out and back in; and hashed, written, read back,
    # hashed again (a state is copied at every prefix end, the shorter ones again: counted twice).
    MEMORY_BYTES_PER_S = 2e9
    STORE_BYTES_PER_S = 4e8
    KEEP_SHARE = 0.2
    _DECIDE_TOKENS = 64

    _states: MemoryStates
    prefix_store: PrefixStore | None
    n_ctx: int
    _tokens: list[int]  # what the cache holds
    evaluated_tokens: int
    keeps_states: bool | None = None  # None until decided (see above)
    stores_states: bool | None = None

    def prefill(self, context: Sequence[int], prefixes: Sequence[int]) -> int:
        """Make the cache hold ``context``; returns how many of its tokens were not evaluated now. Without
        prefixes (a stage that goes on in the context the one before left), the cache is kept as it is."""
        ends = [end for end in prefixes if 0 < end < min(len(context), self.n_ctx)]
        evaluated = self.evaluated_tokens
        loaded = self._load_prefixes(context, ends) if ends and self.keeps_states is not False else None
        self.sync(context)
        self._settle(drafts=True)
        return loaded if loaded is not None else len(context) - (self.evaluated_tokens - evaluated)

    def _decide_keeping(self, tokens: int, seconds: float) -> None:
        """Whether keeping states pays, from a prefix's last ``tokens`` evaluated in ``seconds``."""
        if tokens < self._DECIDE_TOKENS or seconds <= 0 or not self._tokens:
            return
        per_token = 2 * self._state_bytes() / len(self._tokens)
        budget = self.KEEP_SHARE * seconds / tokens
        self.keeps_states = per_token / self.MEMORY_BYTES_PER_S <= budget
        self.stores_states = self.keeps_states and per_token / self.STORE_BYTES_PER_S <= budget

    def _stored(self, lookup: bool = False) -> PrefixStore | None:
        """The store, where keeping states there pays (or is not decided yet); for a ``lookup``, only if it holds
        any."""
        store = self.prefix_store if self.stores_states is not False else None
        return None if store is None or (lookup and not store.has_entries()) else store

    def _load_prefixes(self, context: Sequence[int], ends: Sequence[int]) -> int:
        """Make the cache hold ``context[:ends[-1]]``: from the longest of the prefixes ending at ``ends`` that
        has a kept state (in memory or the store), each longer one then evaluated on its own, snapshotted,
        loaded back and kept. Returns how many tokens were not evaluated now."""
        if not ends:
            return 0
        start, reused = 0, 0
        for depth, prefix, state in self._kept(context, ends):
            if self._restore(prefix, state):
                self._states.put(prefix, state, self._state_size(state))
                self._touch([list(context[:end]) for end in ends[:depth]])
                start, reused = depth + 1, len(prefix)
                break
        else:
            self._truncate(0)
        for end in ends[start:]:
            prefix = list(context[:end])
            piece = prefix[len(self._tokens):]
            started = time.perf_counter()
            self.evaluate(piece)
            self._settle()
            if self.keeps_states is None:
                self._decide_keeping(len(piece), time.perf_counter() - started)
            if self.keeps_states is False:
                continue
            state = self._snapshot()
            if not self._restore(prefix, state):
                raise ModelError("the backend could not load back the state it had just saved")
            self._states.put(prefix, state, self._state_size(state))
            if (store := self._stored()) is not None:
                store.save(self._store_key(prefix), prefix, state)
        return reused

    def _kept(self, context: Sequence[int], ends: Sequence[int]) -> Iterator[tuple[int, list[int], Any]]:
        """The kept states (in memory or the store) of the prefixes of ``context`` ending at ``ends``, longest
        first: (its index in ``ends``, the prefix, its state)."""
        for depth in reversed(range(len(ends))):
            prefix = list(context[: ends[depth]])
            state = self._states.get(prefix)
            store = self._stored(lookup=True) if state is None else None
            if store is not None:
                state = store.load(self._store_key(prefix), prefix)
            if state is not None:
                yield depth, prefix, state

    def kept_state(self, context: Sequence[int], prefixes: Sequence[int]) -> tuple[list[int], Any] | None:
        """The longest of ``context``'s prefixes (ending at ``prefixes``) whose state is kept, and that state; None
        where none is (lanes of a llama.cpp backend load it into a sequence of their own)."""
        if self.keeps_states is False:
            return None
        ends = [end for end in prefixes if 0 < end < min(len(context), self.n_ctx)]
        found = next(self._kept(context, ends), None)
        return None if found is None else (found[1], found[2])

    def _touch(self, prefixes: Sequence[list[int]]) -> None:
        """Mark shorter prefixes used with a longer one, so that bounded stores keep them as long."""
        for prefix in prefixes:
            self._states.touch(prefix)
            if (store := self._stored(lookup=True)) is not None:
                store.touch(self._store_key(prefix))

    # hooks
    def sync(self, context: Sequence[int]) -> None:
        raise NotImplementedError

    def _truncate(self, size: int) -> None:
        raise NotImplementedError

    def evaluate(self, tokens: list[int]) -> None:
        raise NotImplementedError

    def _settle(self, drafts: bool = False) -> None:
        """Evaluate now what :meth:`evaluate` left for later (a backend that evaluates lazily), with ``drafts`` after
        it where the backend drafts."""

    def _snapshot(self) -> Any:
        """The cache's state (it holds exactly the prefix)."""
        raise NotImplementedError

    def _restore(self, prefix: list[int], state: Any) -> bool:
        """Load a kept state; False (the cache left empty) where the backend refuses it."""
        raise NotImplementedError

    def _state_size(self, state: Any) -> int:
        raise NotImplementedError

    def _state_bytes(self) -> int:
        """The size of the cache's state now, without copying it."""
        raise NotImplementedError

    def _store_key(self, prefix: Sequence[int]) -> str:
        raise NotImplementedError
