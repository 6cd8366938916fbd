"""Following text through a grammar, character by character: what a line may still become, and the
characters it forces next (which backends write in one batch instead of sampling them a token at a
time)."""

from __future__ import annotations

from collections import deque
from weakref import WeakKeyDictionary

from .grammar import Alt, Chars, Grammar, Lit, Node, Ref, Seq

FREE_TEXT_CHARS = 20  # a run of more kinds of character than this is free text (not digits, not a name's first letter)


class _Automaton:
    """A Thompson automaton of a (finite) grammar: states, their edges, the free-text states, the end.

    Built once per grammar (a stage asks about one line's grammar several times, and lanes share them)."""

    def __init__(self, grammar: Grammar):
        self.edges: list[list[tuple[frozenset[str] | None, int]]] = []  # state -> (chars or epsilon, target)
        self.free: set[int] = set()  # the states of free text (a run of any of many characters)
        start, self.accept = self._build(grammar.rules["root"], grammar.rules)
        self.start = self.closure({start})
        self._distance: list[float] | None = None

    def _state(self) -> int:
        self.edges.append([])
        return len(self.edges) - 1

    def _build(self, node: Node, rules: dict[str, Node]) -> tuple[int, int]:
        if isinstance(node, Ref):
            return self._build(rules[node.name], rules)
        start = self._state()
        if isinstance(node, Lit):
            current = start
            for c in node.text:
                nxt = self._state()
                self.edges[current].append((frozenset(c), nxt))
                current = nxt
            return start, current
        if isinstance(node, Chars):
            end = self._state()
            self.edges[start].append((node.chars, end))
            return start, end
        if isinstance(node, Seq):
            current = start
            for item in node.items:
                s, e = self._build(item, rules)
                self.edges[current].append((None, s))
                current = e
            return start, current
        if isinstance(node, Alt):
            end = self._state()
            for option in node.options:
                s, e = self._build(option, rules)
                self.edges[start].append((None, s))
                self.edges[e].append((None, end))
            return start, end
        first = start
        end = self._state()
        current = start
        for k in range(node.max):
            if k >= node.min:
                self.edges[current].append((None, end))
            s, e = self._build(node.item, rules)
            self.edges[current].append((None, s))
            current = e
        self.edges[current].append((None, end))
        if isinstance(node.item, Chars) and len(node.item.chars) > FREE_TEXT_CHARS:
            self.free.update(range(first, len(self.edges)))
        return start, end

    def closure(self, states: set[int]) -> frozenset[int]:
        stack, seen = list(states), set(states)
        while stack:
            for label, target in self.edges[stack.pop()]:
                if label is None and target not in seen:
                    seen.add(target)
                    stack.append(target)
        return frozenset(seen)

    def labels(self, states: frozenset[int]) -> set[frozenset[str]]:
        """The character sets of the edges that leave ``states``."""
        return {label for s in states for label, _ in self.edges[s] if label is not None}

    def step(self, states: frozenset[int], c: str) -> frozenset[int]:
        return self.closure({t for s in states for label, t in self.edges[s] if label is not None and c in label})

    def distances(self) -> list[float]:
        """Each state's fewest characters to the end of the text (0-1 breadth-first, backwards)."""
        if self._distance is None:
            into: list[list[tuple[bool, int]]] = [[] for _ in self.edges]
            for s, edges in enumerate(self.edges):
                for label, t in edges:
                    into[t].append((label is not None, s))
            distance = [float("inf")] * len(self.edges)
            distance[self.accept] = 0
            queue = deque([self.accept])
            while queue:
                t = queue.popleft()
                for step, s in into[t]:
                    if distance[t] + step < distance[s]:
                        distance[s] = distance[t] + step
                        queue.append(s) if step else queue.appendleft(s)
            self._distance = distance
        return self._distance


_AUTOMATA: WeakKeyDictionary[Grammar, _Automaton] = WeakKeyDictionary()


def _automaton(grammar: Grammar) -> _Automaton:
    automaton = _AUTOMATA.get(grammar)
    if automaton is None:
        automaton = _AUTOMATA[grammar] = _Automaton(grammar)
    return automaton


class Matcher:
    """Follows text through a grammar, character by character, and says what must come next.

    A walk through the grammar's automaton: backends use it to write the characters a grammar forces
    (``robots[`` after ``SwitchOn(``...) in one batch instead of sampling them one token at a time.
    """

    def __init__(self, grammar: Grammar):
        self._automaton = _automaton(grammar)
        self._states = self._automaton.start

    def advance(self, text: str) -> bool:
        """Consume ``text``; False (and no change) if the grammar does not allow it."""
        states = self._states
        for c in text:
            states = self._automaton.step(states, c)
            if not states:
                return False
        self._states = states
        return True

    @property
    def accepting(self) -> bool:
        return self._automaton.accept in self._states

    def next_chars(self) -> frozenset[str]:
        """The characters the grammar admits next (none at the end of the text)."""
        return frozenset().union(*self._automaton.labels(self._states))

    def shortest_way(self) -> str:
        """How free text that has run on long enough ends soonest: the characters every shortest way from
        here to the end of the text begins with, until they leave the free text or come to a choice."""
        automaton = self._automaton
        distance = automaton.distances()
        out: list[str] = []
        states = self._states
        while states & automaton.free and (nearest := min(distance[s] for s in states)) > 0:
            c = _only_char({label for s in states if distance[s] == nearest
                            for label, t in automaton.edges[s] if label is not None and distance[t] == nearest - 1})
            if c is None:
                break
            out.append(c)
            states = automaton.step(states, c)
        return "".join(out)

    def forced(self) -> str:
        """The characters that must come next, up to the first choice (or the end)."""
        automaton = self._automaton
        out: list[str] = []
        states = self._states
        while automaton.accept not in states:
            c = _only_char(automaton.labels(states))
            if c is None:
                break
            out.append(c)
            states = automaton.step(states, c)
        return "".join(out)


def _only_char(labels: set[frozenset[str]]) -> str | None:
    """The character the edges leaving a set of states all take, or None where they offer a choice."""
    if len(labels) != 1 or len(label := next(iter(labels))) != 1:
        return None
    return next(iter(label))
