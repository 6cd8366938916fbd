"""Grammars as data, and what we do with them: GBNF for llama.cpp and llguidance,
a regular expression to test membership, random sampling, the longest string, and the only one.

Every grammar here is finite-depth: rules may refer to other rules but never,
directly or not, to themselves, and every repetition is bounded. That keeps
llama.cpp's sampler away from the recursion and nested-repetition cases that
crash or overflow it, lets a grammar be checked by a plain regex, and bounds
the length of every string it admits, so generation always ends by completing
the grammar rather than by running out of tokens.
"""

from __future__ import annotations

import random
import re
import string
from collections.abc import Iterable
from dataclasses import dataclass
from functools import cached_property

from ...errors import SmartLLMError


class GrammarError(SmartLLMError):
    """A grammar is malformed (undefined rule, recursion, bad repetition)."""


@dataclass(frozen=True)
class Lit:
    text: str


@dataclass(frozen=True)
class Chars:
    """One character from a set (printable ASCII only)."""

    chars: frozenset[str]


@dataclass(frozen=True)
class Ref:
    name: str


@dataclass(frozen=True)
class Seq:
    items: tuple[Node, ...]


@dataclass(frozen=True)
class Alt:
    options: tuple[Node, ...]


@dataclass(frozen=True)
class Rep:
    item: Node
    min: int
    max: int


Node = Lit | Chars | Ref | Seq | Alt | Rep
NodeLike = Node | str
_EMPTY = Lit("")


def _node(x: NodeLike) -> Node:
    return Lit(x) if isinstance(x, str) else x


def seq(*items: NodeLike) -> Node:
    """Items in order; empty items (a repetition of at most zero) are left out, since llguidance
    rejects ``{0,0}``."""
    nodes = tuple(n for n in (_node(i) for i in items) if n != _EMPTY) or (_EMPTY,)
    return nodes[0] if len(nodes) == 1 else Seq(nodes)


def alt(*options: NodeLike) -> Node:
    nodes = tuple(dict.fromkeys(_node(o) for o in options))
    if not nodes:
        raise GrammarError("an alternation needs at least one option")
    return nodes[0] if len(nodes) == 1 else Alt(nodes)


def rep(item: NodeLike, low: int, high: int) -> Node:
    if not 0 <= low <= high:
        raise GrammarError(f"repetition {{{low},{high}}} is empty or negative")
    return _EMPTY if high == 0 else Rep(_node(item), low, high)


def opt(item: NodeLike) -> Node:
    return Rep(_node(item), 0, 1)


def chars(allowed: Iterable[str]) -> Chars:
    allowed = frozenset(allowed)
    bad = [c for c in allowed if c not in string.printable or c in "\t\n\r\x0b\x0c"]
    if bad or not allowed:
        raise GrammarError(f"character classes hold printable ASCII without newlines only, got {sorted(bad)!r}")
    return Chars(allowed)


_RULE_NAME = re.compile(r"^[a-z][a-z0-9-]*$")


class Grammar:
    """Named rules; ``root`` is where a string starts."""

    def __init__(self, rules: dict[str, NodeLike]):
        self.rules: dict[str, Node] = {name: _node(node) for name, node in rules.items()}
        self._check()

    def _check(self) -> None:
        if "root" not in self.rules:
            raise GrammarError("a grammar needs a root rule")
        for name in self.rules:
            if not _RULE_NAME.match(name):
                raise GrammarError(f"rule name {name!r}: use lowercase letters, digits and hyphens")
        state: dict[str, int] = {}

        def visit(name: str, path: tuple[str, ...]) -> None:
            if name not in self.rules:
                raise GrammarError(f"rule {path[-1] if path else 'root'} refers to undefined rule {name!r}")
            if state.get(name) == 2:
                return
            if state.get(name) == 1:
                raise GrammarError(f"rules must not recurse: {' -> '.join(path + (name,))}")
            state[name] = 1
            for ref in _refs(self.rules[name]):
                visit(ref, path + (name,))
            state[name] = 2

        visit("root", ())

    # ------------------------------------------------------------------ GBNF

    def to_gbnf(self) -> str:
        """llama.cpp's GBNF; every rule reachable from root, root first."""
        return "\n".join(f"{name} ::= {_gbnf(node)}" for name, node in self._reachable()) + "\n"

    def _reachable(self) -> list[tuple[str, Node]]:
        order: list[str] = []

        def visit(name: str) -> None:
            if name in order:
                return
            order.append(name)
            for ref in _refs(self.rules[name]):
                visit(ref)

        visit("root")
        return [(n, self.rules[n]) for n in order]

    # ---------------------------------------------------------------- others

    @cached_property
    def regex(self) -> re.Pattern[str]:
        return re.compile(self._regex(self.rules["root"]), re.DOTALL)

    def _regex(self, node: Node) -> str:
        if isinstance(node, Lit):
            return re.escape(node.text)
        if isinstance(node, Chars):
            return "[" + "".join(re.escape(c) for c in sorted(node.chars)) + "]"
        if isinstance(node, Ref):
            return "(?:" + self._regex(self.rules[node.name]) + ")"
        if isinstance(node, Seq):
            return "".join(self._regex(i) for i in node.items)
        if isinstance(node, Alt):
            return "(?:" + "|".join(self._regex(o) for o in node.options) + ")"
        return f"(?:{self._regex(node.item)}){{{node.min},{node.max}}}"

    def matches(self, text: str) -> bool:
        """Whether the grammar admits exactly ``text``."""
        return self.regex.fullmatch(text) is not None

    def max_length(self) -> int:
        """The length of the longest string the grammar admits."""
        return self._length(self.rules["root"], {}, True)

    def _length(self, node: Node, memo: dict[str, int], longest: bool) -> int:
        """The length of the longest (or shortest) string ``node`` admits."""
        if isinstance(node, Lit):
            return len(node.text)
        if isinstance(node, Chars):
            return 1
        if isinstance(node, Ref):
            if node.name not in memo:
                memo[node.name] = self._length(self.rules[node.name], memo, longest)
            return memo[node.name]
        if isinstance(node, Seq):
            return sum(self._length(i, memo, longest) for i in node.items)
        if isinstance(node, Alt):
            return (max if longest else min)(self._length(o, memo, longest) for o in node.options)
        return (node.max if longest else node.min) * self._length(node.item, memo, longest)

    def only(self) -> str | None:
        """The one string the grammar admits; None where it admits several (or where finding out would mean
        comparing them: a repetition of varying count)."""
        return self._only(self.rules["root"])

    def _only(self, node: Node) -> str | None:
        if isinstance(node, Lit):
            return node.text
        if isinstance(node, Chars):
            return next(iter(node.chars)) if len(node.chars) == 1 else None
        if isinstance(node, Ref):
            return self._only(self.rules[node.name])
        if isinstance(node, Seq):
            parts = [self._only(item) for item in node.items]
            return None if None in parts else "".join(parts)  # type: ignore[arg-type]
        if isinstance(node, Alt):
            texts = {self._only(option) for option in node.options}
            return texts.pop() if len(texts) == 1 else None
        item = self._only(node.item)
        return item * node.max if item is not None and (node.min == node.max or item == "") else None

    def sample(self, rng: random.Random, extreme: str = "") -> str:
        """A random string of the grammar: uniform choices and repetition counts, or, with
        ``extreme="longest"`` / ``"shortest"``, a random one among the longest / shortest strings
        (the adversaries that test budget bookkeeping)."""
        if extreme not in ("", "longest", "shortest"):
            raise ValueError(f"extreme must be '', 'longest' or 'shortest', not {extreme!r}")
        out: list[str] = []
        self._sample(self.rules["root"], rng, out, extreme, {})
        return "".join(out)

    def _sample(self, node: Node, rng: random.Random, out: list[str], extreme: str, memo: dict[str, int]) -> None:
        if isinstance(node, Lit):
            out.append(node.text)
        elif isinstance(node, Chars):
            out.append(rng.choice(sorted(node.chars)))
        elif isinstance(node, Ref):
            self._sample(self.rules[node.name], rng, out, extreme, memo)
        elif isinstance(node, Seq):
            for item in node.items:
                self._sample(item, rng, out, extreme, memo)
        elif isinstance(node, Alt):
            options = node.options
            if extreme:
                lengths = [self._length(o, memo, extreme == "longest") for o in options]
                best = max(lengths) if extreme == "longest" else min(lengths)
                options = tuple(o for o, n in zip(options, lengths) if n == best)
            self._sample(rng.choice(options), rng, out, extreme, memo)
        else:
            count = {"": rng.randint(node.min, node.max), "longest": node.max, "shortest": node.min}[extreme]
            for _ in range(count):
                self._sample(node.item, rng, out, extreme, memo)

    def after(self, prefix: str) -> Grammar:
        """The grammar of what may follow ``prefix`` (its derivative): how a server is asked to go on with a
        line the planner has begun, so that it admits exactly the tokens the whole grammar admits there.
        Only the rules ``prefix`` runs through are rewritten; the rest stay as references."""
        shortest: dict[str, int] = {}  # each rule's shortest string, for what may be skipped
        node: Node | None = self.rules["root"]
        for c in prefix:
            node = self._derive(node, c, shortest)
            if node is None:
                raise GrammarError(f"{prefix!r} does not begin a string of this grammar")
        return Grammar({**self.rules, "root": node})

    def _derive(self, node: Node, c: str, shortest: dict[str, int]) -> Node | None:
        """What ``node`` admits after the character ``c`` (None: nothing; Brzozowski's derivative)."""
        if isinstance(node, Lit):
            return Lit(node.text[1:]) if node.text[:1] == c else None
        if isinstance(node, Chars):
            return _EMPTY if c in node.chars else None
        if isinstance(node, Ref):
            return self._derive(self.rules[node.name], c, shortest)
        if isinstance(node, Alt):
            options = [d for d in (self._derive(o, c, shortest) for o in node.options) if d is not None]
            return alt(*options) if options else None
        if isinstance(node, Seq):
            options = []
            for i, item in enumerate(node.items):
                derived = self._derive(item, c, shortest)
                if derived is not None:
                    options.append(seq(derived, *node.items[i + 1:]))
                if self._length(item, shortest, False):  # not to be skipped: nothing later starts here
                    break
            return alt(*options) if options else None
        derived = self._derive(node.item, c, shortest)
        return None if derived is None else seq(derived, rep(node.item, max(node.min - 1, 0), node.max - 1))


def _refs(node: Node) -> Iterable[str]:
    if isinstance(node, Ref):
        yield node.name
    elif isinstance(node, Seq):
        for i in node.items:
            yield from _refs(i)
    elif isinstance(node, Alt):
        for o in node.options:
            yield from _refs(o)
    elif isinstance(node, Rep):
        yield from _refs(node.item)


_HEX_DIGITS = frozenset("0123456789abcdefABCDEF")


class _Escaper:
    """Characters as every GBNF reader reads them (llama.cpp, llguidance, vLLM's XGrammar): as themselves where
    they can be, else ``\\xHH``. XGrammar reads every hex digit that follows ``\\x`` (llama.cpp and llguidance
    read two), so a hex digit right after such an escape is escaped too. Characters past ASCII are written as
    themselves (UTF-8), which all three read; a ``\\x`` escape holds one byte's worth."""

    def __init__(self, in_class: bool):
        self.in_class, self.after_escape = in_class, False

    def __call__(self, c: str) -> str:
        if c == "\n" and not self.in_class:
            self.after_escape = False
            return "\\n"
        plain = c.isalnum() or c == " " or c >= "\x80" or (not self.in_class and c not in '"\\')
        if plain and not (self.after_escape and c in _HEX_DIGITS):
            self.after_escape = False
            return c
        self.after_escape = True
        return f"\\x{ord(c):02X}"


def _literal(text: str) -> str:
    escape = _Escaper(in_class=False)
    return '"' + "".join(escape(c) for c in text) + '"'


def _class(allowed: frozenset[str]) -> str:
    codes = sorted(ord(c) for c in allowed)
    escape = _Escaper(in_class=True)
    parts: list[str] = []
    i = 0
    while i < len(codes):
        j = i
        while j + 1 < len(codes) and codes[j + 1] == codes[j] + 1:
            j += 1
        if j - i >= 2:
            first = escape(chr(codes[i]))
            escape.after_escape = False  # a '-' comes between
            parts.append(f"{first}-{escape(chr(codes[j]))}")
        else:
            parts.extend(escape(chr(c)) for c in codes[i:j + 1])
        i = j + 1
    return "[" + "".join(parts) + "]"


def _gbnf(node: Node) -> str:
    if isinstance(node, Lit):
        return _literal(node.text)
    if isinstance(node, Chars):
        return _class(node.chars)
    if isinstance(node, Ref):
        return node.name
    if isinstance(node, Seq):
        return " ".join(_gbnf_atom(i) for i in node.items)
    if isinstance(node, Alt):
        return " | ".join(_gbnf(o) for o in node.options)
    inner = _gbnf_atom(node.item)
    if (node.min, node.max) == (0, 1):
        return f"{inner}?"
    if node.min == node.max:
        return f"{inner}{{{node.min}}}"
    return f"{inner}{{{node.min},{node.max}}}"


def _gbnf_atom(node: Node) -> str:
    text = _gbnf(node)
    return f"({text})" if isinstance(node, (Alt, Seq)) else text
