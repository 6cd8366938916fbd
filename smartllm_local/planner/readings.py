"""Two readings of one instruction by the same model: its goal statement, and where its decomposition leaves things.

The goal stage says in one breath what must hold; the decomposition says it step by step, each step checked in the
dry-run world as it is written. They fail differently: asked to put the laptop "in the nightstand drawer", the
1.5B states ``Laptop in SideTable`` and writes ``PutObject('Laptop', 'Drawer')``. Where the steps put a thing the
instruction names into a holder it names, the goal has the thing there; a state (on, off, sliced ...) is taken from
the statement alone, since the decomposition's state changes are mostly its means (a fridge opened, a coffee machine
left on) rather than what was asked. Measured on the development half (docs/measurements.md).
"""

from __future__ import annotations

from collections.abc import Collection, Sequence

from ..plan_language import Plan
from ..scene import SceneObjects
from ..scoring import Condition
from ..skills import SkillSet
from ..world.object_types import base_type
from .asked import named_apart
from .constraints.format import MAX_SUBTASKS
from .constraints.world_check import WorldCheck, held
from .verifier import run_subtasks


def placements(plan: Plan, scene: SceneObjects, skills: SkillSet, instruction: str) -> list[Condition]:
    """Where the decomposition's dry run (a robot per sub-task, in order) puts the things the instruction names,
    in holders it names too (not by a word of another thing's name: "the desk lamp" names no desk, "the potato" no
    pot): one ``Holder contains Thing`` per thing in a holder it was not in before (a slice counts as its whole; a
    thing carried or let fall is in none). A holder the instruction never names is the
    steps' means (a potato warmed in a mug because the microwave is out of reach), not what was asked."""
    world = WorldCheck(scene, skills, MAX_SUBTASKS)
    before = held(world.objects())
    run_subtasks(world, plan)
    after = held(world.objects())
    types = scene.types
    return sorted({Condition(holder, item=item) for (item, holder) in after - before
                   if named_apart(instruction, item, types) and named_apart(instruction, holder, types)},
                  key=lambda c: (c.item or "", c.subject))


def may_place(instruction: str, scene: SceneObjects) -> bool:
    """Whether :func:`placements` could find anything here: it reads only holders the instruction names, so an
    instruction that names none of the scene's receptacles (the only things that hold others) has no steps worth
    writing for it ("chop the lettuce and switch the light off")."""
    return any(named_apart(instruction, holder, scene.types) for holder in scene.types_for("receptacle"))


def merge(stated: Sequence[Condition], placed: Sequence[Condition]) -> list[Condition]:
    """The statement with the steps' holders: a thing the steps placed is where they placed it (its stated
    holders dropped), and a holder stated empty that the steps fill is no longer said to be empty."""
    moved = {base_type(c.item or "") for c in placed}
    filled = {c.subject for c in placed}
    kept = [c for c in stated if not ((c.item is not None and base_type(c.item) in moved)
                                      or (c.state == "EMPTY" and c.subject in filled))]
    return kept + [c for c in placed if c not in kept]


def unsettled(placed: Sequence[Condition], stated: Sequence[Condition], asked_into: Collection[str]) -> list[Condition]:
    """The steps' placements of things the statement does not put in a holder the instruction asks things into in
    so many words (``asked_into``: "throw the cloth away", the GarbageCan): asked to throw the cloth away and to put
    the soap in the sink, the 1.5B's steps put both in the sink's basin."""
    settled = {base_type(c.item) for c in stated if c.item is not None and c.subject in asked_into}
    return [c for c in placed if base_type(c.item or "") not in settled]
