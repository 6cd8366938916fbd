"""The goal stage's prompt: worked examples of goal statements, then the task's scene and instruction.

A domain's goal examples are in ``prompts/goal/``: ``examples.json`` lists each one's name, instruction
and scene (an iTHOR floor plan, or the domain's site), and ``<name>.txt`` holds its statement;
``asked_states.toml`` (optional) gives the words by which an instruction asks for each state (see
:mod:`.asked_words`). Each
example shows its scene's whole object list, as the task's own is shown, so that the model learns to
pick from a scene what the instruction is about rather than to name every object listed.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from ...errors import UserError
from ...goal_language import STATE_WORDS
from ...scene import GoalTerms, SceneObjects
from ..constraints.goal import goal_vocabulary
from .prompts import Prompt

GOAL_FOLDER = "goal"


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
