"""The goal stage's prompt: worked examples of goal statements, then the task's scene and instruction.

A domain's goal examples are in ``prompts/goal/``: ``examples.json`` lists each one's name, instruction
and scene (an iTHOR floor plan, or the domain's site), and ``<name>.txt`` holds its statement;
``asked_states.toml`` (optional) gives the words by which an instruction asks for each state (see
:func:`load_state_words`). Each
example shows its scene's whole object list, as the task's own is shown, so that the model learns to
pick from a scene what the instruction is about rather than to name every object listed.
"""

from __future__ import annotations

import functools
import json
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

from ...errors import UserError
from ...goal_language import STATE_WORDS
from ...scene import GoalTerms, SceneObjects
from ..constraints.goal import goal_vocabulary
from .prompts import Prompt

GOAL_FOLDER = "goal"
ASKED_STATES = "asked_states.toml"
#: The table of ``asked_states.toml`` whose states are offered only where asked for, and never owed.
ONLY_WHERE_ASKED = "only_where_asked"
#: The table of ``asked_states.toml`` naming the holders an instruction asks things into in so many words.
PLACEMENTS = "placements"
#: The table of ``asked_states.toml`` whose patterns find a thing put in a holder the instruction names: its
#: ``into`` patterns, each with a ``things`` group and a ``holder`` group.
PUT, PUT_INTO, PUT_GROUPS = "put", "into", frozenset({"things", "holder"})
_TYPE_NAME = re.compile(r"[A-Z][A-Za-z0-9]*")
_CLAUSE = re.compile(r"[,.;:!?]")
_SENTENCE = re.compile(r"[.;:!?]")


@dataclass(frozen=True)
class GoalExample:
    name: str
    instruction: str
    floor_plan: int | str
    statement: str  # its goal statement, as the stage writes it


def load_goal_examples(prompts: Path) -> list[GoalExample]:
    """The goal examples of a domain's ``prompts`` folder, in the order its goal/examples.json lists them."""
    folder = prompts / GOAL_FOLDER
    index = folder / "examples.json"
    try:
        entries = json.loads(index.read_text(encoding="utf-8"))["examples"]
        examples = []
        for entry in entries:
            path = folder / f"{entry['name']}.txt"
            examples.append(GoalExample(entry["name"], entry["instruction"], entry["floor_plan"],
                                        path.read_text(encoding="utf-8")))
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise UserError(f"cannot read the goal examples in {folder}: {exc}; the goal stage needs "
                        f"{index} listing each example's name, instruction and floor_plan, and a "
                        "<name>.txt holding its goal statement") from exc
    return examples


@dataclass(frozen=True)
class StateWords:
    """A domain's ``prompts/goal/asked_states.toml``, each state with its patterns (matched case-insensitively
    against an instruction): ``asked``, the states an instruction asks for in so many words (owed where the model
    leaves them out); ``only_where_asked``, its ``[only_where_asked]`` table, the states the goal grammar offers only
    where the instruction asks for them (never owed); ``placements``, its ``[placements]`` table, the holders an
    instruction asks things into in so many words ("throw the cloth away": the GarbageCan), each thing the asking
    words name owed a line that puts it there; ``put``, its ``[put]`` table's ``into`` patterns, which find the
    things put in a holder the instruction names ("put the potato in the pot"), owed the same way."""

    asked: dict[str, tuple[re.Pattern[str], ...]]
    only_where_asked: dict[str, tuple[re.Pattern[str], ...]]
    placements: dict[str, tuple[re.Pattern[str], ...]]
    put: tuple[re.Pattern[str], ...] = ()


def load_state_words(prompts: Path) -> StateWords:
    """The domain's state words (none where there is no such file): ``STATE = ['<regular expression>', ...]`` a
    line, the same lines under ``[only_where_asked]``, and ``Holder = [...]`` lines under ``[placements]``. Parsed
    once per text of the file: every goal statement and goal check reads them."""
    path = prompts / GOAL_FOLDER / ASKED_STATES
    if not path.is_file():
        return StateWords({}, {}, {})
    try:
        return _parse_state_words(path.read_text(encoding="utf-8"))
    except (OSError, ValueError, TypeError, re.error) as exc:
        raise UserError(f"cannot read {path}: {exc}; write each state as STATE = ['<regular expression>', ...] "
                        "and each holder under [placements] as Holder = [...], or remove the file") from exc


@functools.lru_cache(maxsize=16)
def _parse_state_words(text: str) -> StateWords:
    table = tomllib.loads(text)
    only, placements, put = table.pop(ONLY_WHERE_ASKED, {}), table.pop(PLACEMENTS, {}), table.pop(PUT, {})
    for name, part in ((ONLY_WHERE_ASKED, only), (PLACEMENTS, placements), (PUT, put)):
        if not isinstance(part, dict):
            raise ValueError(f"[{name}] is not a table")
    into = _patterns(put, PUT_INTO.__eq__, f"'{PUT_INTO}'").get(PUT_INTO, ())
    if any(set(p.groupindex) != PUT_GROUPS for p in into):
        raise ValueError(f"each [{PUT}] pattern needs a (?P<things>...) group and a (?P<holder>...) group")
    return StateWords(_patterns(table), _patterns(only),
                      _patterns(placements, _TYPE_NAME.fullmatch, "a holder's type name (GarbageCan)"), into)


def _patterns(table: Mapping[str, Any], known: Callable[[str], object] = STATE_WORDS.__contains__,
              what: str = f"a state ({', '.join(STATE_WORDS)})") -> dict[str, tuple[re.Pattern[str], ...]]:
    patterns = {}
    for key, listed in table.items():
        if not known(key) or not isinstance(listed, list):
            raise ValueError(f"{key!r} is not {what} with a list of patterns")
        patterns[key] = tuple(re.compile(p, re.IGNORECASE) for p in listed)
    return patterns


def states_asked(instruction: str, patterns: Mapping[str, Sequence[re.Pattern[str]]]) -> dict[str, str]:
    """The states the instruction asks for in so many words, each with the words after the asking verb to the end
    of their clause, which name what is to be in it ("fry the potato in a pan, and ...": COOKED, "the potato in a
    pan"); the verb names nothing ("switch the TV on" does not ask for the LightSwitch on)."""
    asked = {}
    for state, listed in patterns.items():
        found = [m for p in listed for m in p.finditer(instruction)]
        if found:
            asked[state] = " ".join(_after_verb(instruction[m.start():m.end()]) +
                                    _CLAUSE.split(instruction[m.end():], 1)[0] for m in found).strip()
    return asked


def without_asking_verbs(instruction: str, patterns: Mapping[str, Sequence[re.Pattern[str]]]) -> str:
    """The instruction with the verb of each state it asks for blanked out: the verb names nothing ("switch off the
    lamp" names no LightSwitch)."""
    spans = sorted({(m.start(), m.start() + len(m[0].split(maxsplit=1)[0]))
                    for listed in patterns.values() for p in listed for m in p.finditer(instruction) if m[0].strip()})
    text = instruction
    for start, end in reversed(spans):
        text = text[:start] + " " * (end - start) + text[end:]
    return text


def puts(instruction: str, patterns: Sequence[re.Pattern[str]]) -> list[tuple[str, str, str]]:
    """The things put somewhere the instruction names, as (the words naming the things, the words naming where,
    the words of the sentence before them), one for each match of ``patterns`` ("close the laptop and put it in
    the drawer": "it", "drawer", "close the laptop and")."""
    return [(m["things"], m["holder"], _SENTENCE.split(instruction[:m.start()])[-1])
            for p in patterns for m in p.finditer(instruction)]


def _after_verb(words: str) -> str:
    return words.split(maxsplit=1)[1] if " " in words.strip() else ""


def goal_intro(terms: GoalTerms) -> str:
    """The rules, in the terms of the task's world: what a condition names, and the states it knows."""
    thing = terms.thing
    words = ", ".join(STATE_WORDS[s] for s in terms.states)
    containment = f' or "<{thing.capitalize()}> in <Receptacle>"' if terms.containment else ""
    return f"""\
# For each task below, write what must be true once it is done, one condition per line:
# "<{thing.capitalize()}> <state>"{containment}, naming only the {thing}s listed.
# The states: {words}. Say only what the task asks for; a blank line ends the list.
# If the task cannot be done here, answer with one line: # INFEASIBLE: <why>.
"""


def names_list(scene: SceneObjects) -> str:
    """The scene's objects that a goal may name, as a Python list."""
    return repr(list(goal_vocabulary(scene).types))


def goal_prompt(instruction: str, scene: SceneObjects, examples: Sequence[GoalExample]) -> Prompt:
    """The prompt in parts, as the decomposition's: examples, the scene's objects, the task's own words."""
    parts = [goal_intro(scene.world.goal_terms())]
    for k, ex in enumerate(examples, start=1):
        seen = scene.world.scene(ex.floor_plan)
        parts.append(f"\n# Example {k}\nobjects = {names_list(seen)}\n# Task Description: {ex.instruction}\n"
                     f"# Goal:\n{ex.statement.rstrip()}\n")
    return Prompt(("".join(parts) + "\n# Your", f" task\nobjects = {names_list(scene)}\n# Task",
                   f" Description: {instruction}\n# Goal:\n"))
