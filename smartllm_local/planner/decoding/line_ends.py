"""Line ends as a model writes them: spaces before the newline, and the start of what follows in the same token.

A constraint offers one line at a time, each ending in a newline. Models do not cut their text there: code
tokenizers merge a newline with the spaces and newlines around it (Qwen2.5-Coder writes ``')\\n\\n`` to end a
function, `` \\n\\n`` after a line it is done with, ``\\n   `` before an indented line). So the grammar a backend
is given for a line has its end opened: any spaces before the newline (Python ignores them), and after it,
within the same token, what may start what follows (``follow``: blank lines, an indentation, a ``#``, as the
constraint says for each kind of line). The plan text is normalized as it is read: trailing spaces dropped, a
blank line that ends nothing read as none.
"""

from __future__ import annotations

from .grammar import Alt, Grammar, Lit, Node, Ref, Rep, Seq, alt, rep, seq

#: Spaces a line may end with before its newline (Python ignores them; tokenizers merge them with it).
TRAILING_SPACES = 8
#: Blank lines that may follow a line's newline in the same token (``\\n\\n\\n\\n`` is one of Qwen's tokens).
BLANK_LINES = 3

BLANKS: Node = rep("\n", 0, BLANK_LINES)
#: After a line whose next line is indented (a function's header and body lines, indented by four spaces).
INDENTED_NEXT: Node = alt(BLANKS, rep(" ", 1, 4))
#: After a line whose next line is a comment at the start of the line (a summary line, a coalition line).
COMMENT_NEXT: Node = alt(BLANKS, "#")
#: The most characters an opened end adds to a line beyond those the constraint counts.
MOST_ADDED = TRAILING_SPACES + max(BLANK_LINES, 4)


def open_ends(options: dict[str, Node | str], rules: dict[str, Node], follows: dict[str, Node]) -> Grammar:
    """The grammar of a line whose options (each ending in a newline) have their ends opened: each option's
    newline may have spaces before it and, after it, what ``follows`` says for that kind (blank lines if not
    said)."""
    return Grammar({**rules, "root": alt(*opened(options, rules, follows).values())})


def opened(options: dict[str, Node | str], rules: dict[str, Node], follows: dict[str, Node]) -> dict[str, Node]:
    """Each option of a line with its end opened (see :func:`open_ends`), by kind."""
    return {kind: _open(seq(node), rules, _line_end(follows.get(kind, BLANKS)), {}) for kind, node in options.items()}


def _line_end(follow: Node) -> Node:
    return seq(rep(" ", 0, TRAILING_SPACES), "\n", follow)


def _open(node: Node, rules: dict[str, Node], end: Node, memo: dict[str, bool]) -> Node:
    """``node`` with each newline (in lines, only the last character) replaced by ``end``. Rules that hold a
    newline are written out in place, so that each kind of line gets its own end."""
    if isinstance(node, Lit):
        if "\n" not in node.text:
            return node
        if node.text.index("\n") != len(node.text) - 1:
            raise ValueError(f"a line's grammar has a newline inside a line: {node.text!r}")
        return seq(node.text[:-1], end)
    if isinstance(node, Ref):
        return _open(rules[node.name], rules, end, memo) if _has_newline(node, rules, memo) else node
    if isinstance(node, Seq):
        return seq(*(_open(item, rules, end, memo) for item in node.items))
    if isinstance(node, Rep):
        if _has_newline(node.item, rules, memo):
            raise ValueError("a line's grammar repeats a newline")
        return node
    if isinstance(node, Alt):
        return alt(*(_open(option, rules, end, memo) for option in node.options))
    return node


def _has_newline(node: Node, rules: dict[str, Node], memo: dict[str, bool]) -> bool:
    if isinstance(node, Lit):
        return "\n" in node.text
    if isinstance(node, Ref):
        if node.name not in memo:
            memo[node.name] = _has_newline(rules[node.name], rules, memo)
        return memo[node.name]
    if isinstance(node, Seq):
        return any(_has_newline(item, rules, memo) for item in node.items)
    if isinstance(node, Rep):
        return _has_newline(node.item, rules, memo)
    return isinstance(node, Alt) and any(_has_newline(option, rules, memo) for option in node.options)


def split_spill(spill: str) -> tuple[int, str]:
    """What followed a line's newline in its last token: how many blank lines, and the start of the next line."""
    *blank, rest = spill.split("\n")
    if any(blank):
        raise ValueError(f"not blank lines: {spill!r}")
    return len(blank), rest


