"""Whether an instruction names what a stated goal is about: the goal check refuses a task for a goal out of the
team's reach only where the instruction asked for it, the goal stage's refusal stands only where it is not
for something the instruction names and the scene has, and among several statements the goal stage keeps one
that says something of each thing the instruction names in full, and its grammar offers no thing the instruction's
words name only as part of another thing's name (:func:`outnamed`).

The goal stage states goals from the instruction and the scene; a small model also states goals nobody asked
for (an object the instruction never names). Refusing a feasible task for one of those is refusing it for the
model's invention. So a goal out of reach that nobody asked for (no object of it named by the instruction, none in
a goal that is; or a named thing's place that the instruction does not ask for) is dropped, not refused, where the
statement keeps a goal within reach that was asked for (there is still something asked to plan for); where a goal
out of reach was asked for, or nothing asked for is left, the task is refused as before.

Naming is read generously, since a goal wrongly taken as named is refused as before (the cost of the old rule)
while one wrongly taken as invented is dropped: an object type is named where a word of its name (``DeskLamp``:
desk, lamp) is a word of the instruction or shares its first :data:`PREFIX` letters with one that names no type of
its own ("telly" names the Television; "stove" names the StoveBurner, not the Stool). A goal on two objects
(``Apple in Fridge``) is named where either is.
"""

from __future__ import annotations

import re
from collections.abc import Collection, Iterable, Mapping, Sequence
from functools import cache

from ..goal_language import name_words
from ..scoring import Condition, Goal
from ..world.object_types import (
    CALLED_BY_WHOLE,
    COLD_SOURCES,
    HEAT_SOURCES,
    INFORMAL_NAMES,
    PUT_IN_PART,
    RECEPTACLE_ONLY_ACCEPTS,
    TYPE_PROPERTIES,
    WATER_BASINS,
    base_type,
    informal_names,
)

#: How many first letters a word of the instruction and a word of a type's name must share.
PREFIX = 3
_WORD = re.compile(r"[a-z]+")
#: Words a noun follows (one or two words on).
_DETERMINERS = frozenset({"the", "a", "an", "my", "your", "our", "its", "his", "her", "their", "this", "that", "these",
                          "those", "some", "any", "every", "each"})
#: The holders that give what they hold a state, each with the states it gives (heat, cold, a burner's pan frying, a
#: basin under a running faucet rinsing and filling).
GIVES = {**{h: frozenset({"HOT", "COOKED"}) for h in HEAT_SOURCES | RECEPTACLE_ONLY_ACCEPTS["StoveBurner"]},
         **{h: frozenset({"COLD"}) for h in COLD_SOURCES}, **{h: frozenset({"CLEAN", "FILLED"}) for h in WATER_BASINS},
         "CoffeeMachine": frozenset({"HOT", "FILLED"})}
#: Holders that give what they hold a state: where a thing goes in one of them is no mere place ("chill the apple":
#: the fridge; "fry an egg": the pan on the burner).
STATE_GIVING = frozenset(GIVES)
#: Words after which an instruction names where a thing is now, not where it must be ("from the coffee table").
ORIGIN = re.compile(r"\b(?:from|out of)\s+(?:the\s+|a\s+|an\s+|my\s+|your\s+)?([a-z]+(?:\s+[a-z]+)?)")


def names(instruction: str, object_type: str, *, loosely: bool = False) -> bool:
    """Whether the instruction names the object type (or the type it is a slice of), by a word of its name (a
    plural's ending aside), an informal name ("the TV": the Television) or a word in a noun's place sharing the first
    letters of a word of its name that names no type of its own ("the telly"; "the stove" names no Stool, "the pot"
    no Potato); ``loosely``, such a word anywhere ("toast the bread" names the Toaster)."""
    words = _WORD.findall(instruction.lower())
    said = set(words)
    nouns = said if loosely else _after_determiners(words)
    own = type_words(object_type)
    for word in said:
        forms = word_forms([word])
        if forms.intersection(own) or word in nouns and not forms & _own_words() and any(
                min(len(word), len(w)) >= PREFIX and word[:PREFIX] == w[:PREFIX] for w in own):
            return True
    return _informally(said, object_type)


def _after_determiners(words: Sequence[str]) -> set[str]:
    """The words in a noun's place, one or two after a determiner ("the telly", "the old telly"): only there does a
    word sharing a type's first letters name it ("should" named the ShowerHead, "could" the CounterTop, "both" the
    Bottle: dev11-e4 was refused for a `ShowerHead on` nobody asked for)."""
    return {w for n, d in enumerate(words) if d in _DETERMINERS for w in words[n + 1:n + 3]}


@cache
def _own_words() -> frozenset[str]:
    """The words of every known type's name, and every informal name: each names its own types."""
    return frozenset(w for t in TYPE_PROPERTIES for w in type_words(t)) | frozenset(INFORMAL_NAMES)


def names_a_word(instruction: str, object_type: str) -> bool:
    """Whether the instruction says a word of the type's name or an informal name of it (a plural's ending aside):
    read strictly, with no shared first letters ("potato" names the Potato, not the Pot; "for" not the Fork)."""
    said = word_forms(_WORD.findall(instruction.lower()))
    return bool(set(type_words(object_type)) & said) or _informally(said, object_type)


def asks_for(instruction: str, condition: Condition) -> bool:
    """Whether the instruction names an object of the condition (its subject, or what it holds)."""
    return names(instruction, condition.subject) or (condition.item is not None and names(instruction, condition.item))


def invented(instruction: str, out_of_reach: Sequence[Condition], stated: Sequence[Condition],
             asked_into: Collection[str] = (), unsaid: Collection[tuple[str, str]] = ()) -> list[Condition]:
    """The goals out of reach to drop rather than refuse for: all of them where none is asked for and some goal
    within reach is; otherwise none (the task is refused). A goal is asked for where the instruction names one of
    its objects, or where one of them is in a goal asked for ("make me a coffee": ``Mug in CoffeeMachine`` is
    named, so ``Mug filled`` is asked for too); but a named thing's place is the model's choice where the instruction
    neither names the holder nor asks for it in so many words (``asked_into``), and the holder gives what it holds
    no state (:data:`STATE_GIVING`): asked to slice the apple, the 1.5B also put the slices in a bowl, for a team
    that cannot put anything down. So is a state of a thing the instruction asks put somewhere, where it has no
    words for the state (``unsaid``: (thing, state) pairs): asked to take the candle out of the bathtub and put it on
    the counter, the 1.5B stated it there and `Candle on`. ("Put the telly on" puts the TV nowhere: its `on` is
    asked.)"""
    asked = _asked(instruction, stated, asked_into)
    if not out_of_reach or any(c in asked and not placed_by_model(instruction, c, asked_into)
                               and (base_type(c.subject), c.state) not in unsaid for c in out_of_reach):
        return []
    left = [c for c in stated if c not in out_of_reach]
    return list(out_of_reach) if any(c in asked for c in left) else []


def placed_by_model(instruction: str, condition: Condition, asked_into: Collection[str]) -> bool:
    """Whether the condition puts a thing in a holder the instruction neither names nor asks things into
    (``asked_into``) and that gives what it holds no state (:data:`STATE_GIVING`): where the thing goes is the
    model's choice."""
    return _put_freely(condition, asked_into) and not names(instruction, condition.subject)


def brought_by_model(instruction: str, condition: Condition, asked_into: Collection[str]) -> bool:
    """Whether the condition puts a thing the instruction does not name in a holder it asks nothing into and that
    gives what it holds no state: which thing goes there is the model's choice (asked to lift the loo seat, the
    1.5B put the toilet paper in the toilet: dev15-e4)."""
    return _put_freely(condition, asked_into) and not names(instruction, condition.item or "")


def _put_freely(condition: Condition, asked_into: Collection[str]) -> bool:
    """Whether the condition puts a thing in a holder nobody asks things into (``asked_into``) that gives what it
    holds no state (:data:`STATE_GIVING`)."""
    holder = condition.subject
    return condition.item is not None and holder not in asked_into and holder not in STATE_GIVING


def gives_nothing_asked(instruction: str, condition: Condition, states: Mapping[str, Collection[str]],
                        asked_into: Collection[str]) -> bool:
    """Whether the condition puts a thing in a holder that gives states (:data:`GIVES`) none of which the instruction
    asks for (``states``, each with the things its words name; the holder switched on asks for what it gives, "toast
    the bread": the toaster on), that it does not ask things into, and that it names not at all or as a thing whose
    own state it asks for: asked to open the fridge and cut the apple, the 0.5B put the apple in the fridge, which
    chills, for a team that could not put anything down ("keep the slices in the fridge" names it as a place)."""
    holder = condition.subject
    return condition.item is not None and holder in GIVES and holder not in asked_into \
        and not GIVES[holder] & set(states) and holder not in states.get("ON", ()) \
        and (any(holder in things for things in states.values()) or not names(instruction, holder))


def unasked(instruction: str, stated: Sequence[Condition], asked_into: Collection[str] = ()) -> list[Condition]:
    """The stated goals nobody asked for (:func:`invented`'s reading: no object of them named, none in a goal that
    is), where some stated goal was asked for; none where none was."""
    asked = _asked(instruction, stated, asked_into)
    return [c for c in stated if c not in asked] if asked else []


def named_in_full(instruction: str, types: Sequence[str]) -> list[str]:
    """The scene's types every word of whose name the instruction says ("the bar of soap": the SoapBar, not
    the SoapBottle; a plural's ending aside), less those it names only as where a thing comes from ("move the
    laptop from the coffee table"): the things a goal statement should say something of."""
    text = instruction.lower()
    said = word_forms(_WORD.findall(text))
    origin = word_forms(w for match in ORIGIN.finditer(text) for w in match.group(1).split())
    rest = word_forms(_WORD.findall(ORIGIN.sub(" ", text)))
    return [t for t in types if ((words := set(type_words(t))) <= said or _informally(said, t, in_full=True))
            and not (words <= origin and not words <= rest)]


def outnamed(instruction: str, types: Sequence[str]) -> set[str]:
    """The types whose every name word the instruction says belongs to other types it names as a phrase
    (:func:`named_as_phrase`): "the bar of soap" names the SoapBar, so "soap" does not name the SoapBottle; "the
    side table" is not the CoffeeTable; "on the desk" names no DeskLamp. A type whose name holds another's whole
    name is not outnamed by it where it is a kind of the other, its name ending as the other's does ("the chair"
    may be the ArmChair), or a part people call by the other's name ("the sink" may be the SinkBasin). A word said
    again outside the phrase names the type ("draw the shower curtain and switch the shower on": the ShowerHead)."""
    text = instruction.lower()
    phrases = {t: _phrase(t) for t in types if named_as_phrase(instruction, t)}
    said = word_forms(_WORD.findall(text))
    out = set()
    for t in types:
        words = set(type_words(t))
        if not words & said or any(words == set(type_words(p)) for p in phrases):
            continue
        others = [pattern for p, pattern in phrases.items() if not _may_be(t, p)]
        if not words & word_forms(_WORD.findall(_blanked(text, others))):
            out.add(t)
    return out


def _blanked(text: str, patterns: Sequence[re.Pattern[str]]) -> str:
    """The text with each match of ``patterns`` in it blanked out."""
    return blanked_spans(text, [m.span() for pattern in patterns for m in pattern.finditer(text)])


def blanked_spans(text: str, spans: Collection[tuple[int, int]]) -> str:
    """The text with each of the ``(start, end)`` spans blanked out, its other characters where they were."""
    return "".join(" " if any(a <= n < b for a, b in spans) else c for n, c in enumerate(text))


def _may_be(kind: str, named: str) -> bool:
    """Whether a thing of ``kind`` may be what the name of ``named`` means: a kind of it ("the chair": an ArmChair;
    not "the desk": a DeskLamp) or a part called by its name (a SinkBasin)."""
    words, whole = type_words(kind), type_words(named)
    return set(whole) <= set(words) and (words[-1] == whole[-1] or CALLED_BY_WHOLE.get(base_type(kind)) == named)


def named_as_phrase(instruction: str, object_type: str) -> bool:
    """Whether the instruction says the type's name as a phrase: its words in order ("the desk lamp", "coffee
    tables"), a two-word name's words as one ("the basketball", "an armchair"), or its last word, "of", then its
    first ("a bar of soap")."""
    return _phrase(object_type).search(instruction.lower()) is not None


def named_apart(instruction: str, object_type: str, types: Sequence[str]) -> bool:
    """Whether the instruction names the type (:func:`names`) in words that are not part of the phrase of another
    name among ``types`` not within its own ("switch off the desk lamp" names no Desk, "the coffee machine" no
    CoffeeTable; "the sink" may be the SinkBasin), nor where an informal name of it says whose another thing is
    ("the nightstand drawer" names no SideTable, "the TV remote" no Television)."""
    words = set(type_words(object_type))
    others = [other for other in types if not set(type_words(other)) <= words]
    text = instruction.lower()
    informal = [n for n in informal_names(base_type(object_type)) if n not in words]  # "the lamp can go off"
    heads = sorted({w for o in others for w in type_words(o)} - words)
    if informal and heads:
        text = re.sub(rf"\b(?:{'|'.join(informal)})\s+(?=(?:{'|'.join(heads)})(?:e?s)?\b)", " ", text)
    for other in others:
        text = _phrase(other).sub(" ", text)
    return names(text, object_type)


@cache
def _phrase(object_type: str) -> re.Pattern[str]:
    words = [re.escape(w) for w in type_words(object_type)]
    phrase = r"\s+".join(f"{w}(?:e?s)?" for w in words)
    if len(words) == 2:
        phrase += rf"|{words[0]}{words[1]}s?|{words[1]}s?\s+of\s+(?:the\s+|a\s+)?{words[0]}s?"
    return re.compile(rf"\b(?:{phrase})\b")


def things_named(words: str, types: Sequence[str]) -> list[str]:
    """The types ``words`` name as things to move: as a phrase ("the spray bottle") or by an informal name, the
    likeliest of its meanings among ``types`` ("the remote"; "the soap": the bar beside a soap bottle, as the
    benchmark means it, the bottle where it is the only soap; two words as one, "the paper towels": the roll), not
    where they name where a thing comes from ("from the bowl"); a slice type only where its whole is not among them,
    and no type whose name is part of another's named ("the wine bottle" is no Bottle, "the paper towels" no Towel:
    dev8-p4)."""
    text = ORIGIN.sub(" ", words.lower())
    spoken = _WORD.findall(text)
    said = word_forms(spoken) | word_forms(a + b for a, b in zip(spoken, spoken[1:]))  # "paper towels": "papertowels"
    kinds = {base_type(t) for t in types}
    meant = {next((k for k in INFORMAL_NAMES.get(word, ()) if k in kinds), None) for word in said}
    named = [t for t in types if named_as_phrase(text, t) or base_type(t) in meant]
    named = [t for t in named if not any(set(type_words(t)) < set(type_words(n)) for n in named)]  # a wine bottle
    return [t for t in named if base_type(t) == t or base_type(t) not in named]


def holder_named(words: str, holders: Collection[str]) -> str | None:
    """The one holder of ``holders`` that ``words`` name ("the dining table", "the couch"), or None where they name
    none or several: the type named as a phrase with the most words, else the one an informal name means; none
    where another holder whose name holds the one named may be what it means (:func:`_may_be`: "the chair" beside
    an armchair; "the toilet" is no toilet paper hanger) or an informal name means several ("the table" beside a
    coffee table and a side table). A thing put in the sink goes in its basin (:data:`PUT_IN_PART`), whether or
    not the scene's sink is a holder of its own ("put the mug in the sink": the 0.5B put it in the fridge named for
    the apple, and nothing was owed; dev7-c5); one put in the bathtub goes in the bathtub, which holds things itself,
    not its basin (the 1.5B stated the soap bar in the basin, and nothing was owed; dev10-p1)."""
    phrased = [h for h in holders if named_as_phrase(words, h)]
    phrased += [part for whole, part in PUT_IN_PART.items()
                if part in holders and whole not in holders and named_as_phrase(words, whole)]
    if phrased:
        most = max(len(type_words(h)) for h in phrased)
        named = {h for h in phrased if len(type_words(h)) == most}
        named |= {h for h in holders for n in named if set(type_words(n)) < set(type_words(h)) and _may_be(h, n)}
    else:
        said = word_forms(_WORD.findall(words.lower()))
        named = {h for h in holders if _informally(said, h)}
    meant = {PUT_IN_PART.get(h) for h in named} & named or \
        {CALLED_BY_WHOLE.get(h) for h in named} & named - set(PUT_IN_PART)  # a bathtub holds things itself
    return next(iter(named)) if len(named) == 1 else next(iter(meant)) if len(meant) == len(named) - 1 == 1 else None


def coverage(named: Sequence[str], stated: Sequence[Condition]) -> float:
    """The share of the named types (:func:`named_in_full`) that some stated condition is about (1 where none)."""
    about = {base_type(t).lower() for c in stated for t in _objects(c)}
    return sum(base_type(t).lower() in about for t in named) / len(named) if named else 1.0


def present_yet_refused(refusal: str, instruction: str, types: Sequence[str]) -> str | None:
    """A type of the scene that both the goal stage's refusal and the instruction name, or None. The stage sees
    the scene alone, so a refusal can only be for something the scene lacks; one that names what the instruction
    asks for and the scene has ("there is no stove" beside a StoveBurner; "no toaster" for "toast a slice of bread",
    read loosely: a mistaken refusal costs a task, a statement asked for again costs seconds) is the model's mistake.
    A two-word name said as one word names its type in the refusal too ("there is no armchair in this room": the
    goal-planner refused dev15-c4 so)."""
    return next((t for t in types if (names(refusal, t) or named_as_phrase(refusal, t))
                 and names(instruction, t, loosely=True)), None)


def as_goal(condition: Condition) -> Goal:
    """The condition as a goal of its own (the goal check checks each alone)."""
    if condition.state is not None:
        return Goal(condition.subject, state=condition.state)
    return Goal(condition.subject, contains=(condition.item or "",))


def _asked(instruction: str, stated: Sequence[Condition], asked_into: Collection[str]) -> list[Condition]:
    """The stated goals asked for: named by the instruction, or sharing an object with one asked for, where a
    holder the model chose (:func:`_placed_by_model`) is shared by nothing: asked to slice the bread, the 0.5B put
    it in a cabinet and a spoon in the cabinet too."""
    asked: list[Condition] = []
    more = [c for c in stated if asks_for(instruction, c)]
    objects: set[str] = set()
    while more:
        asked += more
        objects |= {base_type(t) for c in more for t in _objects(c)
                    if not (t == c.subject and placed_by_model(instruction, c, asked_into))}
        more = [c for c in stated if c not in asked and objects & {base_type(t) for t in _objects(c)}]
    return asked


def _objects(condition: Condition) -> list[str]:
    return [condition.subject] + ([condition.item] if condition.item else [])


def word_forms(words: Iterable[str]) -> set[str]:
    """The words, and each as it would be without a plural's ending ("glasses": glasse, glass)."""
    forms = set()
    for w in words:
        forms |= {w, w[:-1], w[:-2]} if len(w) > 3 and w.endswith("s") and not w.endswith("ss") else {w}
    return forms


def _informally(said: set[str], object_type: str, *, in_full: bool = False) -> bool:
    """Whether a word said is an informal name of the type (or of the type it is a slice of); ``in_full``: one
    that names it alone and is no word of its name ("the TV": the Television; "the soap" names neither soap in
    full, nor "the lamp" the DeskLamp)."""
    kind = base_type(object_type)
    names = informal_names(kind)
    if in_full:
        names = tuple(n for n in names if INFORMAL_NAMES[n] == (kind,) and n not in type_words(kind))
    return bool(said.intersection(names))


def type_words(object_type: str) -> list[str]:
    """The lowercase words of a type's name (of the type it is a slice of)."""
    return [w.lower() for w in name_words(base_type(object_type))]
