"""What an instruction's words owe the goal statement: the states, holders and placements they ask for in so many
words, in the domain's ``asked_states.toml``, read over the scene's things (:func:`asked_of`). The goal stage owes
them in its grammar and leaves out what nobody asked for; the planner's last sub-task meets them; the goal check
reads them. The model never sees this reading: it is of the instruction alone and the scene as it begins.
"""

from __future__ import annotations

import re
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from ..goal_language import OPPOSITES
from ..scene import GoalVocabulary
from ..scoring import Condition, condition_holds, containment
from ..world.object_types import RECEPTACLE_ONLY_ACCEPTS, TYPE_PROPERTIES, base_type
from .asked import GIVES, holder_named, names, outnamed, things_named
from .prompting.asked_words import (
    Phrase,
    StateWords,
    named_for,
    phrases_asked,
    placements_and_words,
    referred,
    sentence_before,
    states_asked,
    without_asking_verbs,
    without_purpose,
)


def reading_vocabulary(instruction: str, vocabulary: GoalVocabulary, words: StateWords) -> GoalVocabulary:
    """The vocabulary an instruction's goals are stated in: less the things its words name only as part of another's
    name ("the bar of soap" names the SoapBar, not the SoapBottle: :func:`.asked.outnamed`), read without what it
    leaves as it is, and less those ("every light except the floor lamp": the desk lamp, not the floor lamp)."""
    kept = words.excepted_in(instruction, vocabulary.types)
    return vocabulary.less(outnamed(words.without_excepted(instruction), vocabulary.types) | kept)


def standing(objects: Sequence[Mapping[str, Any]]) -> frozenset[tuple[str, str]]:
    """Each (holder type, thing type) of a thing in or on a holder among ``objects``, movable or not (the desk lamp
    on the side table)."""
    kind = {o["objectId"]: o["objectType"] for o in objects}
    return frozenset((kind[holder], kind[thing]) for holder, things in containment(objects).items()
                     for thing in things if holder in kind and thing in kind)


#: The states a switch's verb asks for ("switch", "turn", "power" name nothing).
SWITCHED = ("ON", "OFF")
#: Words that ask a state of every thing the word after them names ("turn off every lamp in the room").
EVERY = re.compile(r"\b(?:every|each|all|both)\s+(?:of\s+)?(?:the\s+)?[a-z]+", re.IGNORECASE)
#: Words that place a thing where it is ("the lamp on the side table").
LOCATED = re.compile(r"\b(?:on|in|inside)\s+(?:the\s+|a\s+|an\s+|my\s+|your\s+)?"
                     r"(?P<holder>[a-z]+(?:\s+[a-z]+)?)", re.IGNORECASE)


@dataclass(frozen=True)
class Asked:
    """What the instruction asks for in so many words: ``states``, each with the things its words name that can be
    in it, and ``placements``, each holder with the things to go in it (both owed where the model leaves them
    out); ``withheld``, the states offered only where asked for, and not asked for; ``naming``, the instruction less
    the verbs of the switches it asks for, whose words name no thing ("switch off the lamp"; None: all of it);
    ``moves``, whether it asks for any thing moved at all (:meth:`StateWords.asks_to_move`); ``each``, the states
    whose words name several things each by a name of its own ("slice the apple, the lettuce and the tomato"), with
    those things, each owed the state (of the others, one is); ``placing``, each holder of ``placements`` with the
    words asking things into it."""

    states: Mapping[str, Sequence[str]]
    withheld: Collection[str]
    placements: Mapping[str, Sequence[str]]
    naming: str | None = None
    moves: bool = True
    each: Mapping[str, Sequence[str]] = field(default_factory=dict)
    placing: Mapping[str, str] = field(default_factory=dict)

    def owes(self, condition: Condition) -> bool:
        """Whether the condition is one the words owe: a thing they name put where they ask it, or in the state."""
        if condition.item is not None:
            return condition.item in self.placements.get(condition.subject, ())
        return condition.subject in self.states.get(condition.state or "", ())

    def whole_of_piece_owed(self, condition: Condition) -> bool:
        """Whether the condition puts a whole thing where the words owe its piece: `Egg in Pan` beside the owed
        `EggCracked in Pan`: a cracked egg is no whole one, and no plan meets both (the goal planner found none for `Egg
        broken` beside `Egg in Pan`: dev13-c6)."""
        return condition.item is not None and \
            any(base_type(t) == condition.item != t for t in self.placements.get(condition.subject, ()))

    def put_elsewhere(self, condition: Condition) -> bool:
        """Whether the condition puts a thing in a holder the instruction asks other things into, by words that do
        not name it ("cut the bread and put the apple in the microwave": ``Bread in Microwave``)."""
        things = self.placements.get(condition.subject)
        return condition.item is not None and bool(things) and base_type(condition.item) not in things \
            and condition.item not in things and not names(self.placing.get(condition.subject, ""), condition.item)


def asked_of(instruction: str, vocabulary: GoalVocabulary, words: StateWords,
             objects: Sequence[Mapping[str, Any]] = ()) -> Asked:
    """What the instruction asks for in so many words, in the domain's ``words``, of the vocabulary's things; of
    several things its words name for a state, those it places where the scene's ``objects`` have them; where they
    name a liquid, the things that hold it, owed filled too (:func:`_holding_liquid`); asked of every light, each
    light not in the state as the scene begins (:func:`_every_light`); nothing of what the person will do once the
    robots are done (:func:`without_purpose`)."""
    instruction = without_purpose(instruction)
    vocabulary = vocabulary.less(words.excepted_in(instruction, vocabulary.types))
    there = standing(objects)
    holders = {holder for holder, _ in there}
    states: dict[str, list[str]] = {}
    each: dict[str, list[str]] = {}
    said_at: dict[tuple[str, str], int] = {}
    for state, phrases in phrases_asked(instruction, words.asked, words.verbs).items():
        said = " ".join(phrase.words for phrase in phrases).strip()
        filled = [s for s in words.filled_by(said) if s != state]
        liquid = _holding_liquid(said, [state, *filled], vocabulary) if filled else {}
        if liquid:  # "boil some water on the stove": a pot, filled and hot (and on the burner: the put's)
            for given, things in liquid.items():
                states[given] = [t for t in states.get(given, things) if t in things] or things
        else:
            named = _named_in_phrases(instruction, state, phrases, vocabulary)
            if not named and all(phrase.own for phrase in phrases):
                continue  # "leave the TV on; the match is still on": the words of a state asked name nothing
            said_at.update({(state, t): at for t, at in named.items()})
            states[state] = _located(said, [t for t in vocabulary.types if t in named], holders, there)
            apart = [t for t in things_named(said, vocabulary.types) if t in states[state]]
            if len(apart) > 1:  # "the desk lamp and the ceiling light", not "the lamp" beside two
                each[state] = apart
            elif len(states[state]) > 1 and (EVERY.search(said) or len(set(named.values())) > 1):
                each[state] = states[state]  # "every lamp"; "light it, and turn on the shower": each its phrase's
    _last_of_opposites(states, each, said_at)
    _every_light(instruction, vocabulary, words, objects, states, each)
    withheld = set(words.only_where_asked) - set(states_asked(instruction, words.only_where_asked))
    switches = {state: words.asked[state] for state in SWITCHED if state in words.asked}
    placements, placing = placements_and_words(instruction, vocabulary, words)
    placements = {holder: [_piece_for(t, holder, states, vocabulary) for t in things]
                  for holder, things in placements.items()}
    for state in CUT_BY_PIECES:
        _cut_by_pieces_placed(state, states, each, placements)
    _vessels_on_burners(states, placements, vocabulary, there)
    return Asked(states, withheld, placements, without_asking_verbs(instruction, switches),
                 words.asks_to_move(instruction), each, placing)


def _named_in_phrases(instruction: str, state: str, phrases: Sequence[Phrase],
                      vocabulary: GoalVocabulary) -> dict[str, int]:
    """The things the phrases asking for a state name (or a pronoun of one stands for, the thing its own sentence
    named before: "if the candle isn't lit, light it, and turn on the shower"), each with where the last of them
    starts."""
    def able(kind: str) -> bool:
        return state in vocabulary.states.get(kind, ())
    named = {}
    for phrase in phrases:
        before = sentence_before(instruction, phrase.at)
        for thing in named_for(phrase.words, able, vocabulary) or \
                ([] if phrase.own else referred(phrase.words, before, able, vocabulary)):
            named[thing] = phrase.at
    return named


def _last_of_opposites(states: dict[str, list[str]], each: dict[str, list[str]],
                       said_at: Mapping[tuple[str, str], int]) -> None:
    """A thing asked for in a state and in its opposite is owed the one said last: "open the fridge, put the lettuce
    on the worktop, and shut the fridge again" owes it shut, not open too."""
    for state, things in list(states.items()):
        opposite = OPPOSITES.get(state, "")
        gone = [t for t in things if (opposite, t) in said_at and said_at[opposite, t] > said_at.get((state, t), -1)]
        if gone:
            states[state] = [t for t in things if t not in gone]
            each[state] = [t for t in each.get(state, ()) if t not in gone]
            for table in (states, each):
                if not table[state]:
                    del table[state]


def _every_light(instruction: str, vocabulary: GoalVocabulary, words: StateWords, objects: Sequence[Mapping[str, Any]],
                 states: dict[str, list[str]], each: dict[str, list[str]]) -> None:
    """Each light of the scene not yet in a state the instruction asks of every light, owed it in place of the lights
    its other words name for it, beside the other things they name: "make it nice and dark in here" owes the ceiling
    light and the floor lamp off where both are on (the 1.5B stated the ceiling light alone: dev13-s1, -s6, -c3)."""
    for state in words.every_light_asked(instruction):
        lights = [t for t in vocabulary.types if t in words.lights and state in vocabulary.states.get(t, ())
                  and not condition_holds(Condition(t, state=state), objects)]
        if lights:
            states[state] = [t for t in states.get(state, ()) if t not in words.lights] + lights
            if len(states[state]) > 1:
                each[state] = states[state]


def _piece_for(thing: str, holder: str, states: Mapping[str, Sequence[str]], vocabulary: GoalVocabulary) -> str:
    """The piece of ``thing`` that goes in the holder, where it can: the piece a state is asked of that the thing
    itself cannot be in ("fry me an egg" owes the cracked egg in the pan, as it owes it cooked), or the one breaking
    the thing makes, the thing asked broken ("crack an egg into the pan": the cracked egg); else the thing."""
    pieces = [t for t in vocabulary.types if base_type(t) == thing != t and holder in vocabulary.holders.get(t, ())]
    for state, named in states.items():
        piece = next((t for t in named if t in pieces), None)
        if piece and state not in vocabulary.states.get(thing, ()):
            return piece
    broken = thing in states.get("BROKEN", ()) and "breakable" in TYPE_PROPERTIES.get(thing, ())
    return pieces[0] if broken and pieces else thing


def _vessels_on_burners(states: Mapping[str, Sequence[str]], placements: dict[str, list[str]],
                        vocabulary: GoalVocabulary, there: Collection[tuple[str, str]]) -> None:
    """A pan (pot, kettle) owed a thing that is to be cooked or heated in it, owed on the heat source that takes
    only such vessels, where none of them holds it yet: "fry me an egg" owes the pan on the stove (dev13-p1, -c1:
    the 1.5B put the egg in the microwave), and so does "cook the potato in the pan on the stove"."""
    for source, vessels in RECEPTACLE_ONLY_ACCEPTS.items():
        heated = {t for state in GIVES.get(source, ()) for t in states.get(state, ())}
        for vessel in sorted(vessels):
            if set(placements.get(vessel, ())) & heated and source in vocabulary.holders.get(vessel, ()) \
                    and (source, vessel) not in there:
                placements[source] = list(dict.fromkeys([*placements.get(source, []), vessel]))


#: The states whose pieces say them: a thing whose pieces are somewhere was cut (broken).
CUT_BY_PIECES = ("SLICED", "BROKEN")


def _cut_by_pieces_placed(state: str, states: dict[str, list[str]], each: dict[str, list[str]],
                          placements: Mapping[str, Sequence[str]]) -> None:
    """A thing whose pieces are put somewhere is owed no line of its own cut (broken): the pieces' line asks for it
    ("put a slice of bread in the toaster" owes `BreadSliced in Toaster`, not `Bread sliced` too: dev12-p6; "crack an
    egg into the pan" `EggCracked in Pan`, not `Egg broken`)."""
    pieces = {base_type(t) for things in placements.values() for t in things if base_type(t) != t}
    cut = [t for t in states.get(state, ()) if t not in pieces]
    if len(cut) == len(states.get(state, ())):
        return
    apart = each.pop(state, [])
    states.pop(state)
    if cut:
        states[state] = cut
    if len(cut) > 1 and apart:
        each[state] = cut


def _holding_liquid(words: str, states: Sequence[str], vocabulary: GoalVocabulary) -> dict[str, list[str]]:
    """Each of ``states`` with the things that can be in all of them (and go in the holder the words first place
    them in, where one is named) that the words name, or every such thing where they name none: the words name a
    liquid, so they mean a thing holding it ("some water on the stove": a pot, not a wine bottle). A holder that can
    be in them itself holds the liquid ("boil water in the pot": the pot)."""
    holders = vocabulary.holder_types()
    where = next((h for m in LOCATED.finditer(words) if (h := holder_named(m["holder"], holders))), None)

    def able(kind: str) -> bool:
        return set(states) <= set(vocabulary.states.get(kind, ())) and \
            (where is None or where in vocabulary.holders.get(kind, ()))

    if where is not None and set(states) <= set(vocabulary.states.get(where, ())):
        return dict.fromkeys(states, [where])
    things = named_for(words, able, vocabulary) or [t for t in vocabulary.types if able(t)]
    return dict.fromkeys(states, things) if things else {}


def _located(words: str, named: list[str], holders: Collection[str], there: Collection[tuple[str, str]]) -> list[str]:
    """Of several things named, those in the first holder the words place them in that holds any of them as the
    scene begins ("the lamp on the side table": the DeskLamp standing there, not the FloorLamp); else all."""
    if len(named) < 2:
        return named
    for where in LOCATED.finditer(words):
        holder = holder_named(where["holder"], holders)
        here = [t for t in named if (holder, t) in there] if holder else []
        if here:
            return here
    return named
