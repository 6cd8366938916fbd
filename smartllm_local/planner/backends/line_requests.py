"""How a server writes a line the way the in-process backend does, one request per stretch of model choices.

In-process, the model chooses tokens one by one; where the grammar forces two or more characters the
planner writes them itself, in one batch (its own tokens, evaluated together), and where a line starts
to loop (:class:`LoopGuard`) it writes the grammar's shortest way out. A server asked for a whole line
would sample the forced text token by token instead, and may spell it with other tokens, after which
the model sees another context. So each request here asks the server to go on with the line from where
it stands (the line's grammar after the text so far, :meth:`Grammar.after`); of its answer, the tokens up
to the next point where the in-process backend would write text itself are kept, the rest dropped, and
the next request carries that text. Given the context as token ids (llama-server), the server then sees
the in-process backend's tokens, and evaluates them in the same batches, request for request.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from ..grammar import Grammar, Matcher
from .base import Generated, Sampling
from .repetition import TRIES, current_line

#: Asks the server to go on: (context, the grammar of what may come next, at most this many tokens, tokens
#: it must not write) -> the tokens it wrote (none: it ended the sequence).
Ask = Callable[[list[int], Grammar, int, Sequence[int]], list[int]]


#: Tokens a server is first asked for at once in a line. It writes on (its answers past the next forced text
#: are dropped, and cost decoding time), so it is asked for few, and for twice as many after an answer that
#: was kept whole.
FIRST_ASK = 8


class WrongLine(Exception):
    """A server wrote text the line's grammar does not allow."""


class LineRequests:
    """One line of a stage, written through a server."""

    def __init__(self, context: Sequence[int], grammar: Grammar, sampling: Sampling, ask: Ask,
                 spell: Callable[[str], list[int]], text_of: Callable[[int], str],
                 taken: Callable[[list[int]], None] = lambda tokens: None):
        """``spell`` gives forced text's tokens, ``text_of`` one token's text; ``taken`` is told each batch the
        in-process backend would evaluate (a forced text, a way out, a chosen token)."""
        self.context, self.grammar, self.ask = list(context), grammar, ask
        self.guard = sampling.loop_guard
        self.spell, self.text_of, self.taken = spell, text_of, taken
        self.matcher = Matcher(grammar)
        self.out: list[int] = []
        self.text, self.loops = "", 0

    def write(self, max_tokens: int) -> Generated:
        stretch = FIRST_ASK
        while len(self.out) < max_tokens:
            forced = self.matcher.forced()
            if len(forced) >= 2:  # as in-process: one character is left to the model
                self._take(self.spell(forced))
            else:
                answer = self._ask(min(max_tokens - len(self.out), stretch), ())
                if not answer:
                    return self._done("eos")
                for token in answer:
                    if self.guard is not None and self.guard.loops(current_line(self.text) + self.text_of(token)):
                        self.loops += 1
                        way = self.matcher.shortest_way()
                        self._take(self.spell(way) if way else [self._instead(token)])
                        break
                    self._take([token])
                    if self.text.endswith("\n") or len(self.out) >= max_tokens or len(self.matcher.forced()) >= 2:
                        break
                else:
                    stretch *= 2  # kept whole: the model is in a long stretch of its own
            if self.text.endswith("\n"):
                return self._done("line")
        return self._done("length")

    def _ask(self, max_tokens: int, banned: Sequence[int]) -> list[int]:
        return self.ask(self.context + self.out, self.grammar.after(self.text), max_tokens, banned)

    def _instead(self, looping: int) -> int:
        """The best admitted token that does not close the loop (asked for with the ones that do banned),
        among the best ``TRIES``; if every one of them does, the best."""
        banned = [looping]
        line = current_line(self.text)
        while len(banned) < TRIES:
            answer = self._ask(1, banned)
            if not answer or not self.guard.loops(line + self.text_of(answer[0])):  # type: ignore[union-attr]
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
        return Generated(self.out, self.text, stop, self.loops)

