"""What an instruction asks for in so many words, in its domain's ``prompts/goal/asked_states.toml``: the states
it asks for, those offered only where asked, the holders it asks things into, and the things it puts in a holder it
names. Read by the goal stage (owed lines, lines left out) and by ``domain check`` (the goal examples)."""

from __future__ import annotations

import functools
import re
from collections.abc import Callable, Collection, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

from ...errors import UserError
from ...goal_language import STATE_WORDS
from ...scene import GoalVocabulary
from ...world.object_types import base_type
from ..asked import blanked_spans, holder_named, named_as_phrase, names_a_word, things_named, type_words, word_forms
from .goal_prompt import GOAL_FOLDER

ASKED_STATES = "asked_states.toml"
#: The table of ``asked_states.toml`` whose states are offered only where asked for (owed only where the file's
#: first table has them too).
ONLY_WHERE_ASKED = "only_where_asked"
#: A state's value under ``[only_where_asked]`` where its words are those of the table above (``OPENED = "as asked"``).
AS_ASKED = "as asked"
#: The table of ``asked_states.toml`` naming the holders an instruction asks things into in so many words.
PLACEMENTS = "placements"
#: The table of ``asked_states.toml`` whose patterns find a liquid, under the state a thing filled with it is in.
LIQUIDS = "liquids"
#: The table of ``asked_states.toml`` whose patterns ask a state of every light of the room (its ``things``).
EVERY_LIGHT, LIGHTS = "every_light", "things"
#: The table of ``asked_states.toml`` whose patterns find a thing put in a holder the instruction names: its
#: ``into`` patterns, each with a ``things`` group and a ``holder`` group; and its ``moves`` patterns, the words that
#: ask for a thing moved at all, a holder named or not ("put the cup away", "tidy the desk").
PUT, PUT_INTO, PUT_GROUPS, PUT_MOVES = "put", "into", frozenset({"things", "holder"}), "moves"
#: The table of ``asked_states.toml`` whose ``words`` patterns find things left as they are ("every light except the
#: floor lamp"), each with a ``things`` group naming them.
EXCEPTED, EXCEPTED_WORDS = "excepted", "words"
#: The group of a state's pattern that holds the words saying what is to be in it where no verb asks ("TV on,
#: please": ``(?P<said>...)``); without one, the words after the pattern's first word (its verb).
SAID = "said"
_TYPE_NAME = re.compile(r"[A-Z][A-Za-z0-9]*")
#: Where the words asking for a state or a holder end: at the end of their part of the sentence, or before the next
#: verb that asks for something (``StateWords.verbs``) once they name something ("cut the bread and put the apple in
#: the microwave": the bread; "slice the apple, the lettuce and the tomato": all three; "wash and slice the apple":
#: the apple, for both).
_PART = re.compile(r"[.;:!?]")
_THEN = re.compile(r"\bthen\b", re.IGNORECASE)
_WORD = re.compile(r"[a-z']+")
_NAMING_NOTHING = frozenset({"and", "or", "then", "also", "the", "a", "an", "please", "now", "too", "both", "all",
                             "some", "of", "on", "off", "away", "out", "up", "down"})
#: Words that join a verb to the words before it ("... and switch", "..., then turn").
_JOINED = re.compile(r"(?:\b(?:and|then)|,)\s+$", re.IGNORECASE)
#: A switch's particle said, then "and" and another thing with its own ("switch the TV on and the floor lamp off"):
#: the words after "and" are the other particle's, and those before it not.
_PARTICLES = "on|off|open|shut|closed"
_PARTICLE_END = re.compile(rf"\b(?P<particle>{_PARTICLES})\s*$", re.IGNORECASE)
_PARTICLE_AND = re.compile(rf"\b(?:{_PARTICLES})\s*,?\s+and\s+", re.IGNORECASE)
_GAPPED_SWITCH = re.compile(
    rf"\s*,?\s*and\s+(?:the|a|an|my|your|this|that|every|each|all|both)\s+(?:[a-z'-]+\s+){{0,3}}?(?P<particle>{_PARTICLES})\b",
    re.IGNORECASE)
#: Words saying what the person will do once the robots are done, which ask nothing of the robots: "turn on the stove
#: so I can fry it" asks for no potato cooked, and puts nothing in a pan.
_PURPOSE = re.compile(r"\b(?:so\s+(?:that\s+)?(?:i|we)\s+(?:can|could|may|might)|for\s+(?:me|us)\s+to)\b[^.;:!?]*",
                      re.IGNORECASE)
#: Where a sentence ends: a pronoun of a put means what was named before it in its sentence, across ";" and ":"
#: ("the potato and the egg are in the sink; put both of them in the fridge").
_SENTENCE = re.compile(r"[.!?]")
#: Pronouns for the one thing, or all the things, the sentence named before ("put it away", "put them on the bed").
_IT, _THEM = re.compile(r"\bit\b", re.IGNORECASE), re.compile(r"\b(?:them|both)\b", re.IGNORECASE)
#: Where a clause of a sentence ends.
_CLAUSE = re.compile(r"[,;:]")
#: A put with its verb left out, after the holder of the one before it: "... in the microwave(,) and the egg in the
#: fridge"; the things' words a phrase a determiner starts, so that "and the lamp on the desk off" is not one.
_GAPPED = re.compile(r"[a-z]+(?:\s+[a-z]+)??\s*,?\s+and\s+"
                     r"(?P<things>(?:the|a|an|my|your|some)\s+[a-z'-]+(?:\s+[a-z'-]+){0,2}?)"
                     r"\s+(?:in|into|inside|on|onto)\s+(?:the\s+|a\s+|an\s+|my\s+|your\s+)?(?:(?:one|any|either)\s+of\s+"
                     r"(?:the\s+)?)?(?P<holder>[a-z]+(?:\s+(?!(?:on|off)\b)[a-z]+)?)\b(?!\s+(?:on|off)\b)",
                     re.IGNORECASE)


@dataclass(frozen=True)
class StateWords:
    """A domain's ``prompts/goal/asked_states.toml``, each state with its patterns (matched case-insensitively
    against an instruction): ``asked``, the states an instruction asks for in so many words (owed where the model
    leaves them out); ``only_where_asked``, its ``[only_where_asked]`` table, the states the goal grammar offers only
    where the instruction asks for them (owed only where ``asked`` has them too); ``placements``, its
    ``[placements]`` table, the holders an instruction asks things into in so many words ("throw the cloth away":
    the GarbageCan), each thing the asking words name owed a line that puts it there; ``put``, its ``[put]`` table's
    ``into`` patterns, which find the things put in a holder the instruction names ("put the potato in the pot"),
    owed the same way; ``moves``, its ``moves`` patterns (none: every instruction may ask for a thing moved);
    ``liquids``, its ``[liquids]`` table, each state a thing filled with a liquid is in with the patterns naming
    the liquid ("boil some water": a thing filled); ``every_light``, its ``[every_light]`` table, each state with the
    patterns that ask it of every light (``lights``: its ``things``) that is not in it ("make the room dark");
    ``excepted``, its ``[excepted]`` table's ``words``, which name the things left as they are ("every light except
    the floor lamp")."""

    asked: dict[str, tuple[re.Pattern[str], ...]]
    only_where_asked: dict[str, tuple[re.Pattern[str], ...]]
    placements: dict[str, tuple[re.Pattern[str], ...]]
    put: tuple[re.Pattern[str], ...] = ()
    moves: tuple[re.Pattern[str], ...] = ()
    liquids: Mapping[str, tuple[re.Pattern[str], ...]] = field(default_factory=dict)
    every_light: Mapping[str, tuple[re.Pattern[str], ...]] = field(default_factory=dict)
    lights: tuple[str, ...] = ()
    excepted: tuple[re.Pattern[str], ...] = ()

    @functools.cached_property
    def verbs(self) -> tuple[re.Pattern[str], ...]:
        """The patterns that begin a phrase asking for something: a state, a holder, a thing moved, or "then"."""
        tables = (*self.asked.values(), *self.placements.values(), *self.every_light.values())
        return (*(p for listed in tables for p in listed), *self.moves, _THEN)

    def unsaid(self, instruction: str) -> set[str]:
        """The states it has words to ask for that the instruction does not use ("put it on the counter" asks for no
        switch on; "make the room dark" asks for off, of every light)."""
        return set(self.asked) - set(_matching(self.asked, instruction)) - set(self.every_light_asked(instruction))

    def every_light_asked(self, instruction: str) -> list[str]:
        """The states the instruction asks of every light ("make the room dark": OFF)."""
        return _matching(self.every_light, instruction)

    def excepted_in(self, instruction: str, types: Sequence[str]) -> set[str]:
        """The types the instruction leaves as they are, those named as a phrase where there are ("switch off every
        light except the floor lamp": the floor lamp, not the desk lamp that "lamp" may mean)."""
        kept = set()
        for words in (m["things"] for p in self.excepted for m in p.finditer(instruction)):
            named = things_named(words, types)
            kept.update([t for t in named if named_as_phrase(words, t)] or named)
        return kept

    def without_excepted(self, instruction: str) -> str:
        """The instruction with the words naming what it leaves as it is blanked out, its other words where they
        were: "except the floor lamp" says nothing of the desk lamp."""
        return blanked_spans(instruction, [m.span("things") for p in self.excepted for m in p.finditer(instruction)])

    def asks_to_move(self, instruction: str) -> bool:
        """Whether the instruction asks for any thing moved (always, where the domain has no ``moves`` words)."""
        return not self.moves or any(p.search(instruction) for p in self.moves)

    def filled_by(self, words: str) -> list[str]:
        """The states of a thing filled with a liquid the words name ("some water on the stove": FILLED)."""
        return _matching(self.liquids, words)


def _matching(table: Mapping[str, Sequence[re.Pattern[str]]], text: str) -> list[str]:
    """The keys of ``table`` some pattern of which the text matches."""
    return [key for key, listed in table.items() if any(p.search(text) for p in listed)]


def load_state_words(prompts: Path) -> StateWords:
    """The domain's state words (none where there is no such file): ``STATE = ['<regular expression>', ...]`` a
    line, the same lines under ``[only_where_asked]`` (or ``STATE = "as asked"``, the words of the table above) and
    ``[liquids]`` and ``[every_light]`` (with its ``things = ["LightSwitch", ...]``), ``Holder = [...]`` lines under
    ``[placements]``, ``into = [...]`` and ``moves = [...]`` under ``[put]``, and ``words = [...]`` under
    ``[excepted]``. Parsed once per text of the file:
    every goal statement and goal check reads them."""
    path = prompts / GOAL_FOLDER / ASKED_STATES
    if not path.is_file():
        return StateWords({}, {}, {})
    try:
        return _parse_state_words(path.read_text(encoding="utf-8"))
    except (OSError, ValueError, TypeError, re.error) as exc:
        raise UserError(f"cannot read {path}: {exc}; write each state as STATE = ['<regular expression>', ...] "
                        "(under [liquids] and [every_light] too, with its things = ['LightSwitch', ...]), each "
                        "holder under [placements] as Holder = [...] and the [put] patterns as into = [...] and "
                        "moves = [...] and the [excepted] ones as words = [...], or remove the file") from exc


@functools.lru_cache(maxsize=16)
def _parse_state_words(text: str) -> StateWords:
    table = tomllib.loads(text)
    only, placements, put = table.pop(ONLY_WHERE_ASKED, {}), table.pop(PLACEMENTS, {}), table.pop(PUT, {})
    liquids, every_light, excepted = table.pop(LIQUIDS, {}), table.pop(EVERY_LIGHT, {}), table.pop(EXCEPTED, {})
    for name, part in ((ONLY_WHERE_ASKED, only), (PLACEMENTS, placements), (PUT, put), (LIQUIDS, liquids),
                       (EVERY_LIGHT, every_light), (EXCEPTED, excepted)):
        if not isinstance(part, dict):
            raise ValueError(f"[{name}] is not a table")
    lights = every_light.pop(LIGHTS, [])
    if not isinstance(lights, list) or not all(isinstance(t, str) and _TYPE_NAME.fullmatch(t) for t in lights):
        raise ValueError(f"[{EVERY_LIGHT}] {LIGHTS} is not a list of type names (LightSwitch)")
    only = {state: table.get(state, listed) if listed == AS_ASKED else listed for state, listed in only.items()}
    put_patterns = _patterns(put, {PUT_INTO, PUT_MOVES}.__contains__, f"'{PUT_INTO}' or '{PUT_MOVES}'")
    asked, only = _patterns(table), _patterns(only)
    if any(set(p.groupindex) - {SAID} for part in (asked, only) for listed in part.values() for p in listed):
        raise ValueError(f"a state's pattern may have no group but (?P<{SAID}>...), the words saying what is asked")
    into = put_patterns.get(PUT_INTO, ())
    if any(set(p.groupindex) != PUT_GROUPS for p in into):
        raise ValueError(f"each [{PUT}] {PUT_INTO} pattern needs a (?P<things>...) group and a (?P<holder>...) group")
    left = _patterns(excepted, {EXCEPTED_WORDS}.__contains__, f"'{EXCEPTED_WORDS}'").get(EXCEPTED_WORDS, ())
    if any(set(p.groupindex) != {"things"} for p in left):
        raise ValueError(f"each [{EXCEPTED}] {EXCEPTED_WORDS} pattern needs a (?P<things>...) group and no other")
    return StateWords(asked, only,
                      _patterns(placements, _TYPE_NAME.fullmatch, "a holder's type name (GarbageCan)"), into,
                      put_patterns.get(PUT_MOVES, ()), _patterns(liquids), _patterns(every_light), tuple(lights),
                      left)


def _patterns(table: Mapping[str, Any], known: Callable[[str], object] = STATE_WORDS.__contains__,
              what: str = f"a state ({', '.join(STATE_WORDS)})") -> dict[str, tuple[re.Pattern[str], ...]]:
    patterns = {}
    for key, listed in table.items():
        if not known(key) or not isinstance(listed, list):
            raise ValueError(f"{key!r} is not {what} with a list of patterns")
        patterns[key] = tuple(re.compile(p, re.IGNORECASE) for p in listed)
    return patterns


def states_asked(instruction: str, patterns: Mapping[str, Sequence[re.Pattern[str]]],
                 verbs: Sequence[re.Pattern[str]] = ()) -> dict[str, str]:
    """The states the instruction asks for in so many words, each with the words after the asking verb to the end
    of their part of the sentence or the next of ``verbs`` after a thing named, which name what is to be in it ("fry
    the potato in a pan, and switch ...": COOKED, "the potato in a pan, and"); the verb names nothing ("switch the TV
    on" does not ask for the LightSwitch on)."""
    return {state: " ".join(phrase.words for phrase in found).strip()
            for state, found in phrases_asked(instruction, patterns, verbs).items()}


class Phrase(NamedTuple):
    """A phrase asking for a state: where it starts, its words (:func:`states_asked`), and whether they are its
    pattern's own (a ``said`` group: "the laptop's been left open"), which name its thing or nothing, with no
    pronoun of an earlier thing."""

    at: int
    words: str
    own: bool


def phrases_asked(instruction: str, patterns: Mapping[str, Sequence[re.Pattern[str]]],
                  verbs: Sequence[re.Pattern[str]] = ()) -> dict[str, list[Phrase]]:
    """:func:`states_asked`, each state with its phrases apart, in the order said (a pronoun of one stands for what
    its own sentence named before it: :func:`sentence_before`)."""
    asked = {}
    for state, listed in patterns.items():
        found = sorted((m for p in listed for m in p.finditer(instruction)), key=lambda m: m.start())
        if found:
            asked[state] = [Phrase(m.start(), _asking_words(instruction, m, verbs), SAID in m.re.groupindex)
                            for m in found]
    return asked


def without_purpose(instruction: str) -> str:
    """The instruction with what the person will do blanked out (:data:`_PURPOSE`), its other words where they were."""
    return _PURPOSE.sub(lambda m: " " * len(m[0]), instruction)


def sentence_before(instruction: str, at: int) -> str:
    """The words of the instruction's sentence before position ``at``."""
    return _SENTENCE.split(instruction[:at])[-1]


def referred(said: str, before: str, able: Callable[[str], bool], vocabulary: GoalVocabulary) -> list[str]:
    """The things a pronoun of a state's asking words (``said``) stands for: "it" or "them" among them, or in their
    clause before the verb ("give it a clean"), means the one thing (or all the things) ``able`` that the sentence
    named before (``before``): "the kettle is empty; fill it up", "the bed is dirty; give it a clean" (dev6-e2: the
    1.5B stated the mug clean). Words that name nothing after the verb, with no pronoun, mean the one thing ``able``
    their clause named before it: "get the bed clean again", "give the dirty bed a wash" (dev11-e3, dev11-inf-3)."""
    clause = _CLAUSE.split(before)[-1]
    if not any(p.search(said) or p.search(clause) for p in (_IT, _THEM)):
        earlier = [] if things_named(said, vocabulary.types) else named_for(clause, able, vocabulary)
        return earlier if len(earlier) == 1 else []
    earlier = named_for(before, able, vocabulary)
    return earlier if len(earlier) == 1 or _THEM.search(said) or _THEM.search(clause) else []


def _asking_words(instruction: str, match: re.Match[str], verbs: Sequence[re.Pattern[str]]) -> str:
    if SAID in match.re.groupindex:  # the pattern's own words, whole ("the desk lamp's still on and ...")
        return match[SAID] or ""
    after = _own_words(_after_verb(match[0]), verbs)
    rest = _PART.split(instruction[match.end():], 1)[0]
    ends, gapped = _PARTICLE_END.search(after), _GAPPED_SWITCH.match(rest)
    if ends and gapped and _particle(gapped) != _particle(ends):
        return after  # "switch the TV on and the floor lamp off": the lamp is the other particle's
    end = match.end()  # searched in place, so that a verb's pattern sees the words before the rest, not its start
    for start in sorted({m.start() - end for p in verbs for m in p.finditer(instruction, end, end + len(rest))}):
        if set(_WORD.findall((after + rest[:start]).lower())) - _NAMING_NOTHING:
            return (after + rest[:start]).rstrip(", ")
    return after + rest


def _particle(match: re.Match[str]) -> str:
    word = match["particle"].lower()
    return "shut" if word == "closed" else word


def _own_words(after: str, verbs: Sequence[re.Pattern[str]]) -> str:
    """The words after an asking verb from the last verb joined to them by "and" or "then", whose they are: "fold the
    laptop shut and switch the floor lamp off" asks the lamp off, not the shut's words (dev12-s2: they named the
    LightSwitch by the verb "switch"); and after another particle and "and", whose they are too ("switch the TV on
    and the floor lamp off": the lamp's, for "off")."""
    starts = [m.start() for p in verbs if p is not _THEN for m in p.finditer(after)
              if m.start() and _JOINED.search(after[:m.start()])]
    after = _after_verb(after[max(starts):]) if starts else after
    return _PARTICLE_AND.split(after)[-1]


def without_asking_verbs(instruction: str, patterns: Mapping[str, Sequence[re.Pattern[str]]]) -> str:
    """The instruction with the verb of each state it asks for blanked out: the verb names nothing ("switch off the
    lamp" names no LightSwitch)."""
    spans = sorted({_verb_span(m) for listed in patterns.values() for p in listed for m in p.finditer(instruction)
                    if m[0].strip()})
    text = instruction
    for start, end in reversed(spans):
        text = text[:start] + " " * (end - start) + text[end:]
    return text


def puts(instruction: str, patterns: Sequence[re.Pattern[str]]) -> list[tuple[str, str, str]]:
    """The things put somewhere the instruction names, as (the words naming the things, the words naming where,
    the words of the sentence before them), one for each match of ``patterns`` ("close the laptop and put it in
    the drawer": "it", "drawer", "close the laptop and") and for each put that follows one with its verb left out
    ("put the mug in the microwave and the egg in the fridge": "the egg", "fridge")."""
    found = []
    for m in (m for p in patterns for m in p.finditer(instruction)):
        found.append((m["things"], m["holder"], sentence_before(instruction, m.start())))
        at = m.start("holder")
        while gapped := _GAPPED.match(instruction, at):
            found.append((gapped["things"], gapped["holder"], sentence_before(instruction, gapped.start("things"))))
            at = gapped.start("holder")
    return found


def _after_verb(words: str) -> str:
    return words.split(maxsplit=1)[1] if " " in words.strip() else ""


def _verb_span(match: re.Match[str]) -> tuple[int, int]:
    """Where a match's verb is: the words before its ``said`` group (none, or a joining "and"), else its first word."""
    if SAID in match.re.groupindex:
        return match.start(), match.start(SAID)
    return match.start(), match.start() + len(match[0].split(maxsplit=1)[0])


def placements_asked(instruction: str, vocabulary: GoalVocabulary, words: StateWords) -> dict[str, list[str]]:
    """The holders of the scene the instruction asks things into in so many words (the domain's ``[placements]``),
    each with the things the asking words name that can go in it ("throw the cloth away": GarbageCan, Cloth), and
    those it puts things in by name (``[put]``: "put the potato in the pot", Pot, Potato), where the words name
    one holder (or "it", the one holder the sentence named before: "turn on the microwave after you put the cup in
    it", dev10-p2) and some thing that can go in it, by name or by a pronoun for the one thing (or all the things) the
    sentence named before ("close the laptop and put it away in the drawer"), or by a liquid (``StateWords.liquids``:
    "boil some water on the stove", the things that can be filled); not "the soap", which may be the bar or the
    bottle, nor "on the table" beside three."""
    return placements_and_words(instruction, vocabulary, words)[0]


def placements_and_words(instruction: str, vocabulary: GoalVocabulary,
                         words: StateWords) -> tuple[dict[str, list[str]], dict[str, str]]:
    """:func:`placements_asked`, and each of its holders with the words that ask things into it ("cut the bread and
    put the apple in the microwave": Microwave, "the apple"; a pronoun's, the words before it too)."""
    placed: dict[str, list[str]] = {}
    said: dict[str, str] = {}
    for holder, named, asking in _placed(instruction, vocabulary, words):
        placed[holder] = list(dict.fromkeys([*placed.get(holder, []), *named]))
        said[holder] = f"{said.get(holder, '')} {asking}".strip()
    return placed, said


def _placed(instruction: str, vocabulary: GoalVocabulary,
            words: StateWords) -> Iterator[tuple[str, list[str], str]]:
    """Each holder asked things into (:func:`placements_asked`), with the things named and the words naming them."""
    for holder, said in states_asked(instruction, words.placements, words.verbs).items():
        if holder in vocabulary.types:
            yield holder, named_for(said, lambda t, h=holder: h in vocabulary.holders.get(t, ()), vocabulary), said
    holders = vocabulary.holder_types()
    for things, where, before in puts(instruction, words.put):
        holder = holder_named(where, holders) or \
            (_holder_before(things, before, vocabulary, holders) if _IT.match(where) else None)
        able = [t for t in vocabulary.types if holder in vocabulary.holders.get(t, ())]
        named = things_named(things, able) if holder else []
        asking = things
        if holder and not named and (_IT.search(things) or _THEM.search(things)):
            earlier = things_named(before, able)  # "close the laptop and put it away in the drawer"
            if len(earlier) > 1 and not _THEM.search(things):  # "throw the plunger out, and take the cloth ... and
                earlier = things_named(_CLAUSE.split(before)[-1], able)  # leave it on the counter": the cloth
            named = earlier if len(earlier) == 1 or _THEM.search(things) else []
            asking = f"{before} {things}"
        filled = set(words.filled_by(things)) if holder and not named else set()
        if filled and not filled <= set(vocabulary.states.get(holder, ())):  # "boil some water on the stove": a pot
            named = [t for t in able if filled <= set(vocabulary.states.get(t, ()))]  # (not "in the pot": the pot)
        if holder and named:
            yield holder, named, asking


def _holder_before(things: str, before: str, vocabulary: GoalVocabulary, holders: Collection[str]) -> str | None:
    """The one holder of ``holders`` the sentence named before a put's "it" that can take a thing ``things`` name
    ("put the pan on the stove, crack an egg into it": the pan, since no egg goes on a burner); where the things name
    none, the one holder named before ("turn on the microwave after you put the cup in it")."""
    named = things_named(things, vocabulary.types)
    able = {h for t in named for h in vocabulary.holders.get(t, ())} if named else holders
    return holder_named(before, able)


def named_for(words: str, able: Callable[[str], bool], vocabulary: GoalVocabulary) -> list[str]:
    """The types a word of the words names (:func:`.asked.names_a_word`) that are ``able`` (can be in the state,
    or go in the holder, asked for); none named only by words of another's name said as a phrase ("the bottle" is
    the Bottle, not the soap bottle, where the scene has one; "the wine bottle" no Bottle: dev9-p2); a slice type
    only where its whole is not among them ("the potato" is the Potato, not its slices)."""
    named = [t for t in vocabulary.types if able(t) and names_a_word(words, t)]
    phrased = [t for t in named if named_as_phrase(words, t)]
    named = [t for t in named if not _within(t, phrased, words)]
    return [t for t in named if base_type(t) == t or base_type(t) not in named]


def _within(kind: str, phrased: Sequence[str], words: str) -> bool:
    """Whether the words name ``kind`` only by words of other types' names said as phrases (``phrased``); one said
    as a phrase itself, only where it is within another's ("the wine bottle": no Bottle)."""
    own = set(type_words(kind))
    wholes = [set(type_words(p)) for p in phrased if p != kind]
    if kind in phrased:
        return any(own < whole for whole in wholes)
    said = own & word_forms(_WORD.findall(words.lower()))
    return bool(said) and said <= set().union(*wholes)
