"""How a server writes a line the way the in-process backend does, one request per stretch of model choices.

In-process (:mod:`...decoding.loop`), the model chooses tokens one by one; where the grammar forces two or
more characters the planner writes them itself, in one batch (its own tokens, evaluated together: the
loop's :func:`forced_tokens`, used here too), and where a line starts to loop (:class:`LoopGuard`) it
writes the grammar's shortest way out. A server asked for a whole line
would sample the forced text token by token instead, and may spell it with other tokens, after which
the model sees another context. So each request here asks the server to go on with the line from where
it stands (the line's grammar after the text so far, :meth:`Grammar.after`); of its answer, the tokens up
to the next point where the in-process backend would write text itself are kept, the rest dropped, and
the next request carries that text. Given the context as token ids (llama-server), the server then sees
the in-process backend's tokens, and evaluates them in the same batches, request for request.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from ...decoding.grammar import Grammar
from ...decoding.loop import forced_tokens
from ...decoding.matcher import Matcher
from ...decoding.repetition import TRIES, current_line
from ...decoding.sampling import Generated, Sampling
from .dialects import TokenProbs

#: Asks the server to go on: (context, the grammar of what may come next, at most this many tokens, tokens
#: it must not write) -> the tokens it wrote (none: it ended the sequence), and their probabilities where the
#: server reports them.
Ask = Callable[[list[int], Grammar, int, Sequence[int]], tuple[list[int], list[TokenProbs] | None]]


#: Tokens a server is first asked for at once in a line. It writes on (its answers past the next forced text
#: are dropped, and cost decoding time; in a plan line most answers are cut after a token or two), so it is
#: asked for few, and for twice as many after an answer that was kept whole (free text: a comment).
FIRST_ASK = 2


class WrongLine(Exception):
    """A server wrote text the line's grammar does not allow."""


class LineRequests:
    """One line of a stage, written through a server."""

    def __init__(self, context: Sequence[int], grammar: Grammar, sampling: Sampling, ask: Ask,
                 spell: Callable[[str], list[int]], text_of: Callable[[int], str],
                 taken: Callable[[list[int]], None] = lambda tokens: None, end_tokens: frozenset[int] = frozenset()):
        """``spell`` gives forced text's tokens, ``text_of`` one token's text; ``taken`` is told each batch the
        in-process backend would evaluate (a forced text, a way out, a chosen token). ``end_tokens``: those
        that end the sequence, which the model may choose where the server reports its likeliest tokens
        (greedy decoding: where one of them is likelier than the token the grammar let it write)."""
        self.context, self.grammar, self.ask = list(context), grammar, ask
        self.guard = sampling.loop_guard
        self.greedy = sampling.temperature <= 0
        self.heal = sampling.aligned
        self.spell, self.text_of, self.taken, self.end_tokens = spell, text_of, taken, end_tokens
        self.matcher = Matcher(grammar)
        self.out: list[int] = []
        self.text = ""
        self.measured = Generated([], "", "")

    def write(self, max_tokens: int, lines: int = 1) -> Generated:
        """The line (``lines`` newlines), as the in-process backend writes it."""
        stretch = FIRST_ASK
        while len(self.out) < max_tokens:
            forced = self._forced()
            if forced:
                self._take(forced)
                self.measured.forced += len(forced)
            else:
                answer, probs = self._ask(min(max_tokens - len(self.out), stretch), ())
                if not answer:
                    return self._done("eos")
                for k, token in enumerate(answer):
                    seen = probs[k] if probs else None
                    end = self._end(token, seen)
                    if end is not None:
                        self._measure(end, seen)
                        return self._done("eos")
                    if self.guard is not None and self.guard.loops(current_line(self.text) + self.text_of(token)):
                        self.measured.loops += 1
                        written = forced_tokens(self.matcher.shortest_way(), self.spell, heal=self.heal, way=True)
                        self.measured.forced += len(written)
                        written = written or [self._instead(token)]
                        self._take(written)
                        break
                    self._measure(token, seen)
                    self._take([token])
                    if self.text.count("\n") >= lines or len(self.out) >= max_tokens or self._forced():
                        break
                else:
                    stretch *= 2  # kept whole: the model is in a long stretch of its own
            if self.text.count("\n") >= lines:
                return self._done("line")
        return self._done("length")

    def _end(self, token: int, probs: TokenProbs | None) -> int | None:
        """The end-of-sequence token the model would rather have written than ``token``, if any (greedy
        decoding, where the server reports its likeliest tokens, as many as ``END_RANK``): as in-process, the
        model ends where the end is among those and likelier than what the grammar let it write."""
        if probs is None or not self.greedy or not self.heal:
            return None
        return next((t for t, p in probs[1] if t in self.end_tokens and p > probs[0]), None)

    def _measure(self, chosen: int, probs: TokenProbs | None) -> None:
        """How far the grammar bent the model at a token it chose, as in-process: whether its likeliest token was
        refused (it would have been chosen), and the chosen token's log-probability."""
        if probs is None:
            return
        logprob, top = probs
        self.measured.choices += 1
        self.measured.refused += bool(top) and top[0][0] != chosen
        self.measured.logprob += next((p for t, p in top if t == chosen), logprob)

    def _forced(self) -> list[int]:
        return forced_tokens(self.matcher.forced(), self.spell, heal=self.heal)

    def _ask(self, max_tokens: int, banned: Sequence[int]) -> tuple[list[int], list[TokenProbs] | None]:
        return self.ask(self.context + self.out, self.grammar.after(self.text), max_tokens, banned)

    def _instead(self, looping: int) -> int:
        """The best admitted token that does not close the loop (asked for with the ones that do banned),
        among the best ``TRIES``; if every one of them does, the best."""
        banned = [looping]
        line = current_line(self.text)
        while len(banned) < TRIES:
            answer, probs = self._ask(1, banned)
            if not answer or not self.guard.loops(line + self.text_of(answer[0])):  # type: ignore[union-attr]
                if answer:
                    self._measure(answer[0], probs[0] if probs else None)
                return answer[0] if answer else looping
            banned.append(answer[0])
        return looping

    def _take(self, tokens: list[int]) -> None:
        piece = "".join(self.text_of(t) for t in tokens)
        if not self.matcher.advance(piece):
            raise WrongLine(self.text + piece)
        self.out.extend(tokens)
        self.text += piece
        self.taken(tokens)

    def _done(self, stop: str) -> Generated:
        found = self.measured
        return Generated(self.out, self.text, stop, found.loops, found.forced, found.choices, found.refused,
                         found.logprob)
