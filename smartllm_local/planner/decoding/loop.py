"""How a token is chosen: the one decoding loop of every in-process backend.

Three parts, as outlines splits them. The model (:class:`TokenModel`) is what a backend supplies: it
tokenizes, evaluates tokens after its cached context and gives the next logits, and it compiles a grammar
into its engine's own token mask (:class:`TokenConstraint`: llama.cpp's grammar sampler, llguidance's
matcher). The planner's grammar is followed alongside by its own :class:`.Matcher`. The generator is
:func:`generate`, the same for every backend; each step it:

1. writes the text the planner's grammar forces itself, all its tokens in one batch but the last, which the
   model writes (token alignment, or healing: the model's token may run on into what follows);
2. else asks the model for its logits and chooses a token (:func:`choose`): greedy takes the likeliest token
   the engine's grammar admits, sampling draws from the masked distribution; the end of sequence is the
   model's to choose wherever it is among its ``END_RANK`` likeliest (the planner completes the output);
3. where that token would make the current line loop (:class:`.LoopGuard`), writes the grammar's shortest
   way out of the free text instead, or else takes the best token that closes no loop;
4. measures how far the grammar bent the model at a token it chose (:func:`measure`);
5. evaluates the tokens, follows their text through the planner's grammar (where the engine's grammar let
   through what the planner's does not, the two disagree: an error), and stops at the ``lines``-th newline,
   a stop string, the end of sequence or ``max_tokens``.

Greedy choice asks the engine's grammar first about the likeliest token alone, then about the 64
likeliest, and masks the whole vocabulary only when none of those is admitted: the same token a full mask
gives (any admitted token outside the top 64 scores lower), at a fraction of the cost on a large
vocabulary (llama.cpp's grammar costs ~60 ms a step over Gemma-3's 262k tokens on two cores). Sampling
draws from the whole distribution and keeps the draw where the grammar admits it (rejection sampling:
exactly the masked distribution), and draws from the masked one only where it does not.

A server (:mod:`..backends.server.line_requests`) cannot be driven token by token; it follows the same
rules from the tokens and probabilities a server reports.
"""

from __future__ import annotations

import codecs
from collections.abc import Callable, Sequence
from typing import Protocol

import numpy as np

from ...errors import GrammarMismatchError, ModelError
from .first_bytes import FirstBytes
from .grammar import Grammar, GrammarError
from .matcher import Matcher
from .repetition import TRIES, current_line, draw
from .sampling import END_RANK, Generated, Sampling, may_end

_TOP = END_RANK  # the candidates looked at before the whole vocabulary is masked


class TokenConstraint(Protocol):
    """A grammar compiled by a backend's engine, over the model's tokens, at the point decoding has reached."""

    name: str  # how errors name the engine's grammar ("llama.cpp's grammar")

    def admits(self, token: int) -> bool:
        """Whether the grammar admits ``token`` next."""

    def mask(self, logits: np.ndarray, ids: np.ndarray | None = None) -> np.ndarray:
        """The scores of ``ids`` (in their order; None: the whole vocabulary) with each token the grammar refuses
        at -inf; ``logits`` are those scores unmasked."""

    def accept(self, token: int) -> bool:
        """Move the grammar past ``token``; False (and no move) where it refuses it."""

    def close(self) -> None:
        """Free what the engine holds for it."""


class TokenModel(Protocol):
    """What a backend implements to decode with :func:`generate`: its tokens, its cache and its grammar engine."""

    n_ctx: int
    n_vocab: int
    end_tokens: frozenset[int]  # the tokens that end a sequence

    def tokenize_continuation(self, text: str) -> list[int]:
        """Tokens that spell exactly ``text`` after a context (see :func:`.continuation_tokens`)."""

    def token_bytes(self, token: int) -> bytes:
        """A token's bytes (a control token's: none)."""

    def sync(self, context: Sequence[int]) -> None:
        """Make the cache hold ``context`` and the next logits be those after it."""

    def evaluate(self, tokens: list[int]) -> None:
        """Evaluate ``tokens`` after what the cache holds; the next logits become those after the last."""

    def next_logits(self) -> np.ndarray:
        """The scores of the next token (float32, one per token of the vocabulary); not changed by the loop."""

    def constrain(self, grammar: Grammar) -> TokenConstraint:
        """``grammar`` compiled by the backend's engine; a :class:`GrammarError` where it rejects it."""

    def first_bytes(self) -> FirstBytes | None:
        """The model's vocabulary by first byte (made once per model, when first asked for); None where the engine's
        whole-vocabulary mask costs no more than one over a few tokens (llguidance's)."""


def generate(model: TokenModel, context: Sequence[int], *, grammar: Grammar | None, max_tokens: int,
             sampling: Sampling, stop: Sequence[str] = (), rng: np.random.Generator | None = None,
             lines: int = 1) -> Generated:
    """Continue ``context`` (see :meth:`.Backend.generate` for what it returns and where it stops)."""
    rng = rng or np.random.default_rng(sampling.seed)
    if len(context) + max_tokens > model.n_ctx:
        max_tokens = model.n_ctx - len(context) - 1
    model.sync(context)
    constraint = model.constrain(grammar) if grammar is not None else None
    try:
        return _Decoding(model, constraint, grammar, sampling, rng).run(max_tokens, stop, lines)
    finally:
        if constraint is not None:
            constraint.close()


def forced_tokens(text: str, spell: Callable[[str], list[int]], *, heal: bool, way: bool = False) -> list[int]:
    """The tokens the planner writes itself of ``text`` its grammar forces (``spell`` gives a text's tokens after a
    context): with ``heal``, all but the last, which the model writes (token alignment: its token may run on into
    what follows). A loop guard's ``way`` out is written whole. One character is left to the model: it costs no
    more chosen than forced."""
    if len(text) < 2 and not way:
        return []
    tokens = spell(text)
    return tokens[:-1] if heal and not way else tokens


class Choice:
    """How the next token is chosen from the logits under the engine's grammar. ``ends`` marks the end-of-sequence
    tokens where the end is always the model's choice (aligned decoding; None: only where the grammar admits it).
    ``narrow`` gives the tokens that can come next (None: any): a whole-vocabulary mask asks the engine about those
    alone (see :mod:`.first_bytes`)."""

    def __init__(self, constraint: TokenConstraint | None, ends: np.ndarray | None, sampling: Sampling,
                 rng: np.random.Generator, narrow: Callable[[], np.ndarray | None] = lambda: None):
        self.constraint, self.ends, self.sampling, self.rng, self.narrow = constraint, ends, sampling, rng, narrow

    def admits(self, token: int) -> bool:
        return self.constraint is None or (self.ends is not None and bool(self.ends[token])) \
            or self.constraint.admits(token)

    def masked(self, logits: np.ndarray) -> np.ndarray:
        """The logits of the whole vocabulary, those the grammar refuses at -inf, the end of sequence the model's
        where it is among its ``END_RANK`` likeliest (see :data:`.END_RANK`)."""
        if self.constraint is None:
            masked = logits.copy()
        elif (ids := self.narrow()) is None:
            masked = self.constraint.mask(logits)
        else:
            masked = np.full(len(logits), -np.inf, dtype=logits.dtype)
            masked[ids] = self.constraint.mask(logits[ids], ids)
        if self.ends is not None:
            for end in np.flatnonzero(self.ends):
                if may_end(logits, int(end)):
                    masked[end] = logits[end]
        return masked

    def choose(self, logits: np.ndarray, avoid: Callable[[int], bool] | None = None) -> int:
        """The next token, greedy or sampled, among those the grammar admits and, where any of them is left,
        those ``avoid`` does not refuse."""
        if not np.isfinite(logits[int(np.argmax(logits))]):
            raise ModelError("the model's scores are not numbers (NaN or infinite logits): its weights, or the build "
                             "that runs them, are broken (on a GPU, see whether --n-gpu-layers 0 runs it)")
        if self.sampling.temperature <= 0:
            return self._greedy(logits, avoid)
        scaled = logits.astype(np.float64) / self.sampling.temperature
        probs = np.exp(scaled - scaled.max())
        probs /= probs.sum()
        token = int(self.rng.choice(len(logits), p=probs))
        if self.admits(token) and not (avoid and avoid(token)):
            return token
        masked = self.masked(logits).astype(np.float64) / self.sampling.temperature if self.constraint else scaled
        if not np.isfinite(masked).any():
            raise GrammarError("the grammar admits no token here")
        return draw(np.exp(masked - masked[np.isfinite(masked)].max()), self.rng, avoid, TRIES)

    def _greedy(self, logits: np.ndarray, avoid: Callable[[int], bool] | None) -> int:
        """The likeliest admitted token, asking the grammar about the likeliest, then the ``_TOP`` likeliest, then
        the whole vocabulary; with ``avoid``, the best of the ``TRIES`` likeliest admitted it does not refuse."""
        best = int(np.argmax(logits))
        if self.admits(best) and not (avoid and avoid(best)):
            return best
        top = np.argpartition(-logits, _TOP)[:_TOP]
        top = top[np.argsort(-logits[top], kind="stable")]
        scores = logits[top]
        if self.constraint is not None:
            scores = self.constraint.mask(scores, top)
            if self.ends is not None:
                scores[self.ends[top]] = logits[top][self.ends[top]]
        admitted = top[np.isfinite(scores)]
        if not len(admitted) or (avoid and len(admitted) < TRIES and all(avoid(int(t)) for t in admitted)):
            masked = self.masked(logits)
            if not np.isfinite(masked).any():
                raise GrammarError("the grammar admits no token here")
            admitted = np.argsort(-masked, kind="stable")[: int(np.isfinite(masked).sum())]
        return next((int(t) for t in admitted[:TRIES] if not (avoid and avoid(int(t)))), int(admitted[0]))

    def measure(self, out: Generated, logits: np.ndarray, token: int) -> None:
        """How far the grammar bent the model at a token it chose: whether its likeliest token was refused, and
        the chosen token's log-probability under the unconstrained model."""
        best = int(np.argmax(logits))
        out.choices += 1
        out.refused += best != token and not self.admits(best)
        top = float(logits[best])
        out.logprob += float(logits[token]) - top - float(np.log(np.exp(logits - top, dtype=np.float64).sum()))


class _Decoding:
    """One call of :func:`generate`: its grammars, its text so far and its counts."""

    def __init__(self, model: TokenModel, constraint: TokenConstraint | None, grammar: Grammar | None,
                 sampling: Sampling, rng: np.random.Generator):
        self.model, self.constraint, self.sampling = model, constraint, sampling
        self.matcher = Matcher(grammar) if grammar is not None else None
        self.eog = np.zeros(model.n_vocab, dtype=bool)
        self.eog[list(model.end_tokens)] = True
        self.choice = Choice(constraint, self.eog if sampling.aligned else None, sampling, rng, self._next_ids)
        self.out = Generated([], "", "length")
        self.decoder = codecs.getincrementaldecoder("utf-8")("replace")  # a character split over tokens waits

    def _next_ids(self) -> np.ndarray | None:
        """The tokens that can come next: those that begin with a character the planner's grammar admits next (None:
        any, where no grammar is followed or a character is half written)."""
        if self.matcher is None or self.decoder.getstate()[0]:
            return None
        index = self.model.first_bytes()
        return None if index is None else index.starting_with(self.matcher.next_chars())

    def run(self, max_tokens: int, stop: Sequence[str], lines: int) -> Generated:
        out, decoder = self.out, self.decoder
        while len(out.tokens) < max_tokens:
            new = self._next_tokens()
            if new is None:
                out.text += decoder.decode(b"", final=True)
                out.stop = "eos"
                return out
            self.model.evaluate(new)
            piece = decoder.decode(b"".join(self.model.token_bytes(t) for t in new))
            if self.matcher is not None and not self.matcher.advance(piece):
                raise GrammarMismatchError(out.text + piece, f"{self.constraint.name} let the model write it, "  # type: ignore[union-attr]
                                           "the planner's grammar does not allow it")
            out.text += piece
            if self.constraint is not None and out.text.count("\n") >= lines:
                out.stop = "line"
                return out
            for s in stop:
                if s in out.text:
                    out.text, out.stop = out.text[: out.text.index(s)], "stop"
                    return out
        out.text += decoder.decode(b"", final=True)
        return out

    def _next_tokens(self) -> list[int] | None:
        """The tokens to write next, accepted by the engine's grammar and counted: text the grammar forces
        (several at once), or the one token the model chooses; None where the model ends the sequence."""
        out, guard, matcher = self.out, self.sampling.loop_guard, self.matcher
        new = self._forced(matcher.forced(), heal=self.sampling.aligned) if matcher else []
        forced = len(new)
        if not new:
            logits = self.model.next_logits()
            token = self.choice.choose(logits)
            line = current_line(out.text)
            if guard is not None and guard.loops(line + self._text(token)):
                # A loop: end the free text it runs in (the grammar's shortest way on), or else take the best
                # token that does not close the loop.
                new = self._forced(matcher.shortest_way(), way=True) if matcher else []
                forced = len(new)
                token = token if new else self.choice.choose(logits, lambda t: guard.loops(line + self._text(t)))
                out.loops += 1
            if not new:
                self.choice.measure(out, logits, token)
        if not new:
            if self.eog[token]:
                return None
            if self.constraint is not None and not self.constraint.accept(token):
                raise GrammarMismatchError(out.text + self._text(token),
                                           f"the model chose it, {self.constraint.name} refuses it")
            new = [token]
        out.tokens.extend(new)
        out.forced += forced
        return new

    def _forced(self, text: str, *, way: bool = False, heal: bool = True) -> list[int]:
        """The :func:`forced_tokens` of ``text``, accepted by the engine's grammar."""
        tokens = forced_tokens(text, self.model.tokenize_continuation, heal=heal, way=way)
        for token in tokens:
            if not self.constraint.accept(token):  # type: ignore[union-attr]
                raise GrammarMismatchError(text, f"the planner's grammar forces it, {self.constraint.name} "  # type: ignore[union-attr]
                                           "refuses it")
        return tokens

    def _text(self, token: int) -> str:
        return self.model.token_bytes(token).decode("utf-8", errors="replace")
