"""The paper's metrics, computed from a run and the world's final state.

- **Exe**: successful actions / attempted actions (every skill call a plan makes
  is an attempted action, ``GoToObject`` included; 0 when nothing was attempted).
- **GCR**: satisfied goal conditions / goal conditions (None for a task that
  has none: an imported task without ground truth can be run, not judged).
- **TCR**: 1 iff GCR = 1.
- **RU**: 1 when the run's transitions equal the ground truth, 0 when they
  reach the task's maximum, linear in between, clipped to [0, 1]; when the
  maximum equals the ground truth, 1 for at most that many transitions and 0
  above. Unknown (None) without a ground truth.
- **SR**: 1 iff TCR = 1 and RU = 1 (None when either is unknown).

Goal conditions come in SMART-LLM's ground-truth shape: ``{"name": type,
"contains": [types], "state": STATE or null}``. Each entry yields one
condition for its state and one per contained type (so a receptacle that must
hold two things gives partial credit), and each condition is counted once: it
holds when some object of the type is in the state, or some receptacle of the
type holds (directly or nested) an object of the contained type. Type names
match case-insensitively after trimming, and a slice of X counts as X. ON and
OFF apply to toggleable objects and to StoveBurners, which are on while the
StoveKnob that controls them is.

Where this differs from the scoring code of the original SMART-LLM release:
that code matches a type as a substring of object names (so "Pan" matches
"PaperTowelRoll"), adds one to the satisfied count for every matching object
and receptacle (GCR can exceed 1), never matches names with stray spaces or
other case, has no BROKEN, CLEAN, DIRTY, COLD, FILLED or EMPTY state, counts
transitions from blank-line-separated code blocks rather than the run, and
counts only object interactions as actions for Exe.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, replace
from typing import Any

from .errors import TaskFileError
from .world.object_types import SLICE_RESULTS, base_type

STATES = (
    "SLICED", "ON", "OFF", "OPENED", "CLOSED", "HOT", "COLD", "COOKED",
    "BROKEN", "PICKED", "CLEAN", "DIRTY", "FILLED", "EMPTY",
)


def _switchable(o: Mapping[str, Any]) -> bool:
    """Toggleable, or a StoveBurner: it is switched through its StoveKnob, and is on while that is."""
    return bool(o.get("toggleable")) or o.get("objectType") == "StoveBurner"


_STATE_TESTS = {
    "ON": lambda o: _switchable(o) and o.get("isToggled"),
    "OFF": lambda o: _switchable(o) and not o.get("isToggled"),
    "OPENED": lambda o: o.get("openable") and o.get("isOpen"),
    "CLOSED": lambda o: o.get("openable") and not o.get("isOpen"),
    "HOT": lambda o: o.get("temperature") == "Hot",
    "COLD": lambda o: o.get("temperature") == "Cold",
    "COOKED": lambda o: o.get("isCooked"),
    "BROKEN": lambda o: o.get("isBroken"),
    "PICKED": lambda o: o.get("isPickedUp"),
    "CLEAN": lambda o: o.get("dirtyable") and not o.get("isDirty"),
    "DIRTY": lambda o: o.get("isDirty"),
    "FILLED": lambda o: o.get("isFilledWithLiquid"),
    "EMPTY": lambda o: o.get("receptacle") and not o.get("receptacleObjectIds"),  # "clear the desk"
}


#: The site simulator's goal states (:mod:`.executor.site`), each with the site entry property it reads.
SITE_STATES = {"COVERED": "isCovered", "PHOTOGRAPHED": "isPhotographed", "RETURNED": "hasWholeTeam"}
_STATE_TESTS.update({state: (lambda o, p=prop: bool(o.get(p))) for state, prop in SITE_STATES.items()})


def normalize_name(name: str) -> str:
    return name.strip().lower()


@dataclass(frozen=True)
class Goal:
    """One ground-truth entry: an object type, what it must contain, and/or a state."""

    name: str
    contains: tuple[str, ...] = ()
    state: str | None = None

    def as_dict(self) -> dict[str, Any]:
        return {"name": self.name, "contains": list(self.contains), "state": self.state}

    def conditions(self) -> list[Condition]:
        out = [Condition(self.name, state=self.state)] if self.state else []
        out += [Condition(self.name, item=item) for item in self.contains]
        return out


@dataclass(frozen=True)
class Condition:
    subject: str
    state: str | None = None
    item: str | None = None

    def describe(self) -> str:
        return f"{self.subject} is {self.state}" if self.state else f"{self.subject} contains {self.item}"


def parse_goals(data: Any, where: str = "goals", states: Sequence[str] = STATES) -> tuple[Goal, ...]:
    """Check and convert a list of goal entries (``states``: those the domain's world has); errors name
    the entry and the field."""
    if not isinstance(data, list):
        raise TaskFileError(f"{where}: expected a list of {{\"name\", \"contains\", \"state\"}} entries")
    goals = []
    for k, entry in enumerate(data):
        at = f"{where}[{k}]"
        if not isinstance(entry, Mapping):
            raise TaskFileError(f"{at}: expected an object with name, contains and state")
        unknown = set(entry) - {"name", "contains", "state"}
        if unknown:
            raise TaskFileError(f"{at}: unknown field(s) {sorted(unknown)}")
        name = entry.get("name")
        if not isinstance(name, str) or not name.strip():
            raise TaskFileError(f"{at}.name: expected an AI2-THOR object type such as \"Fridge\"")
        contains = entry.get("contains", [])
        if contains is None:
            contains = []
        if not isinstance(contains, list) or not all(isinstance(c, str) and c.strip() for c in contains):
            raise TaskFileError(f"{at}.contains: expected a list of object types")
        state = entry.get("state")
        if isinstance(state, str):
            state = state.strip().upper()
            if state in ("", "NONE"):
                state = None
        if state is not None and state not in states:
            raise TaskFileError(f"{at}.state: {entry.get('state')!r} is not one of {', '.join(states)} or null")
        if state is None and not contains:
            raise TaskFileError(f"{at}: a goal needs a state or a non-empty contains list")
        goals.append(Goal(name=name.strip(), contains=tuple(c.strip() for c in contains), state=state))
    return tuple(goals)


def _matches(obj: Mapping[str, Any], wanted: str) -> bool:
    kind = obj["objectType"]
    return kind.lower() == wanted or base_type(kind).lower() == wanted


def as_scored(objects: Sequence[Mapping[str, Any]]) -> list[str]:
    """The objects as the goals see them, sorted: each one's type, the states that hold of it and the types of what
    holds it, whichever of several things of a type it is and wherever it lies. Two ends alike so meet the same goals
    (in a room of two CDs, a robot standing elsewhere takes the other)."""
    kind = {o["objectId"]: o["objectType"] for o in objects}
    holders: dict[str, set[str]] = {}
    for holder, things in containment(objects).items():
        for thing in things:
            holders.setdefault(thing, set()).add(kind.get(holder, holder))
    return sorted(json.dumps([o["objectType"], bool(o.get("isSliced")), sorted(holders.get(o["objectId"], ())),
                              [state for state, test in _STATE_TESTS.items() if test(o)]])
                  for o in objects)


def condition_holds(condition: Condition, objects: Sequence[Mapping[str, Any]],
                    inside: Mapping[str, set[str]] | None = None) -> bool:
    """Whether the final objects satisfy one condition."""
    subject = normalize_name(condition.subject)
    if condition.state == "SLICED":
        pieces = {SLICE_RESULTS[t][0].lower() for t in SLICE_RESULTS if t.lower() == subject}
        return any(
            (o["objectType"].lower() == subject and o.get("isSliced")) or o["objectType"].lower() in pieces
            for o in objects
        )
    if condition.state is not None:
        test = _STATE_TESTS[condition.state]
        return any(_matches(o, subject) and test(o) for o in objects)
    item = normalize_name(condition.item or "")
    inside = inside if inside is not None else containment(objects)
    by_id = {o["objectId"]: o for o in objects}
    return any(
        o["objectType"].lower() == subject and any(_matches(by_id[c], item)
                                                   for c in inside.get(o["objectId"], ()) if c in by_id)
        for o in objects
    )


def containment(objects: Iterable[Mapping[str, Any]]) -> dict[str, set[str]]:
    """receptacle id -> every object inside it, nested contents included."""
    direct: dict[str, set[str]] = {}
    for o in objects:
        for child in o.get("receptacleObjectIds") or []:
            direct.setdefault(o["objectId"], set()).add(child)
        for parent in o.get("parentReceptacles") or []:
            direct.setdefault(parent, set()).add(o["objectId"])
    closure: dict[str, set[str]] = {}
    for rec in direct:
        seen: set[str] = set()
        stack = list(direct[rec])
        while stack:
            cur = stack.pop()
            if cur in seen:
                continue
            seen.add(cur)
            stack.extend(direct.get(cur, ()))
        closure[rec] = seen
    return closure


def robot_utilization(transitions: int, ground_truth: int | None, maximum: int | None) -> float | None:
    """RU per the paper: 1 at the ground truth, 0 at the maximum, linear between, clipped."""
    if ground_truth is None or maximum is None:
        return None
    if maximum <= ground_truth:
        return 1.0 if transitions <= ground_truth else 0.0
    return min(1.0, max(0.0, (maximum - transitions) / (maximum - ground_truth)))


@dataclass(frozen=True)
class Scores:
    SR: float | None
    TCR: float | None
    GCR: float | None
    RU: float | None
    Exe: float
    transitions: int
    conditions: tuple[tuple[str, bool], ...] = ()
    ticks: int = 0  # the run's length (its makespan)
    Speed: float | None = None  # the reference plan's ticks over the run's (see with_speed)

    def with_speed(self, reference_ticks: int | None) -> Scores:
        """RU counts parallel starts, so one robot doing everything in one sub-task scores RU 1; Speed
        shows efficiency: the reference plan's ticks over the run's, capped at 1, for a run that met
        every goal condition (0 for one that did not; None without a reference or goal conditions)."""
        if reference_ticks is None or self.TCR is None:
            return replace(self, Speed=None)
        fast = min(1.0, reference_ticks / self.ticks) if self.ticks else 1.0
        return replace(self, Speed=fast if self.TCR == 1.0 else 0.0)

    def metrics(self) -> dict[str, Any]:
        """The five metrics and the transition count, as the CLI's --json prints them."""
        data = asdict(self)
        for extra in ("conditions", "ticks", "Speed"):
            data.pop(extra)
        return data


def score(
    final_objects: Sequence[Mapping[str, Any]],
    goals: Sequence[Goal],
    *,
    attempted: int,
    succeeded: int,
    transitions: int,
    trans: int | None = None,
    max_trans: int | None = None,
) -> Scores:
    """Score a run from its final objects, its action counts and its transitions."""
    inside = containment(final_objects)
    results = [(c, condition_holds(c, final_objects, inside)) for g in goals for c in g.conditions()]
    gcr = sum(ok for _, ok in results) / len(results) if results else None
    tcr = None if gcr is None else float(gcr == 1.0)
    ru = robot_utilization(transitions, trans, max_trans)
    sr = None if ru is None or tcr is None else float(tcr == 1.0 and ru == 1.0)
    exe = succeeded / attempted if attempted else 0.0
    return Scores(SR=sr, TCR=tcr, GCR=gcr, RU=ru, Exe=exe, transitions=transitions,
                  conditions=tuple((c.describe(), ok) for c, ok in results))


def score_execution(execution: Any, goals: Sequence[Goal], *, trans: int | None = None,
                    max_trans: int | None = None) -> Scores:
    """Score an :class:`~smartllm_local.executor.Execution`."""
    return replace(score(execution.final_objects, goals, attempted=execution.attempted,
                         succeeded=execution.succeeded, transitions=execution.transitions, trans=trans,
                         max_trans=max_trans), ticks=execution.ticks)


__all__ = [
    "SITE_STATES", "STATES", "Goal", "Condition", "Scores", "parse_goals", "condition_holds", "containment",
    "robot_utilization", "score", "score_execution",
]
