"""What an instruction's words ask for where they say it in phrasings the earlier sets did not use: read as the goal
stage reads them (:func:`~smartllm_local.planner.goal_stage.asked_of`), on the eleventh development set's
instructions and words like them."""

from __future__ import annotations

from smartllm_local.domain import load_domain
from smartllm_local.planner.asked import outnamed
from smartllm_local.planner.constraints.goal import goal_vocabulary
from smartllm_local.planner.goal_stage import asked_of
from smartllm_local.planner.prompting.asked_words import load_state_words
from smartllm_local.worlds import scene_objects

WORDS = load_state_words(load_domain("household").prompts_dir())


def _asked(instruction: str, floor_plan: int):
    vocabulary = goal_vocabulary(scene_objects(floor_plan))
    return asked_of(instruction, vocabulary.less(outnamed(instruction, vocabulary.types)), WORDS)


def test_blinds_pulled_up_or_raised_are_open_and_pulled_down_or_lowered_are_shut():
    """"Pull the blinds up" asked for no state (dev11-p3, written so): blinds go up to let the light in."""
    for instruction in ("Pull the blinds up and put the teddy bear on the bed.", "Pull up the blinds.",
                        "Raise the blinds, please.", "Roll the blinds up."):
        assert _asked(instruction, 309).states.get("OPENED") == ["Blinds"], instruction
    for instruction in ("Pull the blinds down.", "Lower the blinds before bed.", "Let the blinds down."):
        assert _asked(instruction, 309).states.get("CLOSED") == ["Blinds"], instruction
    assert "CLOSED" not in _asked("Put the book on the lower shelf.", 309).states
    assert not _asked("Raise the teddy bear onto the bed.", 309).states.get("OPENED")
