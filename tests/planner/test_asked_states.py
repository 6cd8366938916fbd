"""States an instruction asks for in so many words ("fry the potato": cooked) are in every goal statement: a
statement the model ends without one gets a line of it, its thing one the asking words name where they name one."""

from __future__ import annotations

import random
import shutil
from pathlib import Path

import pytest

from smartllm_local.domain import load_domain
from smartllm_local.errors import UserError
from smartllm_local.planner.constraints.goal import GoalConstraint, goal_vocabulary
from smartllm_local.planner.decoding.writer import Report, accepts, run_constraint, run_tokens
from smartllm_local.planner.goal_stage import GOAL_BUDGET
from smartllm_local.planner.prompting.goal_prompt import load_asked_states, states_asked
from smartllm_local.worlds import scene_objects

from .test_goal_stage import TASKS, _check_statement
from .writers import WRITERS, TokenAdversary, writer

PATTERNS = load_asked_states(load_domain("household").prompts_dir())
KITCHEN = goal_vocabulary(scene_objects(1))


@pytest.mark.parametrize(("instruction", "asked"), [
    ("Fry the potato in a pan, and put the bread in the fridge.", {"COOKED": "Fry the potato in a pan"}),
    ("Switch off the lamp on the side table.", {"OFF": "Switch off the lamp on the side table"}),
    ("Move the laptop onto the bed and turn the desk lamp off.", {"OFF": "turn the desk lamp off"}),
    ("Turn on the TV, then shut the laptop.", {"CLOSED": "shut the laptop", "ON": "Turn on the TV"}),
    ("Leave the remote on the sofa and put the TV on.", {}),  # a thing put on a sofa is no state
    ("Could you heat up a potato and chop the tomato?",  # a clause ends at punctuation
     {"SLICED": "chop the tomato", "HOT": "heat up a potato and chop the tomato"}),
])
def test_the_states_an_instruction_asks_for_and_the_words_that_name_their_thing(instruction, asked):
    assert states_asked(instruction, PATTERNS) == asked


def test_a_statement_ended_without_a_state_asked_for_goes_on_with_a_line_of_it():
    asked = {"COOKED": ["Potato"]}
    assert not accepts(GoalConstraint(KITCHEN, asked=asked), "Potato in Pan\n\n")
    assert accepts(GoalConstraint(KITCHEN, asked=asked), "Potato in Pan\n\nPotato cooked\n\n")
    assert accepts(GoalConstraint(KITCHEN, asked=asked), "Potato cooked\nPotato in Pan\n\n")  # said: nothing owed
    # the thing the asking words name, where they name one that can be cooked; any that can, where they do not
    assert not accepts(GoalConstraint(KITCHEN, asked=asked), "Potato in Pan\n\nEggCracked cooked\n\n")
    assert accepts(GoalConstraint(KITCHEN, asked={"COOKED": []}), "Potato in Pan\n\nEggCracked cooked\n\n")
    # a state nothing of the scene can be in asks for nothing
    assert accepts(GoalConstraint(goal_vocabulary(scene_objects(301)), asked={"COOKED": []}), "Laptop in Bed\n\n")
    assert accepts(GoalConstraint(KITCHEN, asked=asked), "# INFEASIBLE: no stove here\n")  # a refusal owes nothing
    # an owed line never contradicts the statement: no holder said to hold a thing is owed empty
    assert not accepts(GoalConstraint(KITCHEN, asked={"EMPTY": ["Fridge"]}), "Apple in Fridge\n\nFridge empty\n\n")
    assert accepts(GoalConstraint(KITCHEN, asked={"EMPTY": ["Fridge"]}), "Apple in Fridge\n\nSink empty\n\n")


@pytest.mark.parametrize("kind", WRITERS)
def test_adversarial_writers_with_states_asked_write_valid_statements_that_state_them(kind):
    rng = random.Random(7)
    for task in TASKS[::3]:
        scene = scene_objects(task.floor_plan)
        vocabulary = goal_vocabulary(scene)
        able = sorted({s for states in vocabulary.states.values() for s in states})
        for seed in range(4):
            asked = {s: rng.sample(vocabulary.types, 2) for s in rng.sample(able, min(2, len(able)))}
            budget = rng.choice([GOAL_BUDGET, GoalConstraint(vocabulary).minimum_budget() + rng.randint(0, 60)])
            constraint = GoalConstraint(vocabulary, asked=asked)
            if seed % 2:
                text = run_tokens(constraint, TokenAdversary(kind, random.Random(seed), refusals=0.1), budget, Report())
            else:
                text = run_constraint(constraint, writer(kind, random.Random(seed), refusals=0.1), len, budget)
            statement = _check_statement(text, scene)
            if statement.refusal is None and budget == GOAL_BUDGET and len(statement.conditions) < 8:
                assert set(asked) <= {c.state for c in statement.conditions}, (asked, text)


def test_a_domain_without_the_file_asks_for_nothing_and_a_bad_file_is_a_clear_error(tmp_path: Path):
    assert load_asked_states(tmp_path) == {}
    (tmp_path / "goal").mkdir()
    (tmp_path / "goal" / "asked_states.toml").write_text("COOKD = ['fry']\n")
    with pytest.raises(UserError, match=r"asked_states\.toml: 'COOKD' is not a state"):
        load_asked_states(tmp_path)
    (tmp_path / "goal" / "asked_states.toml").write_text("COOKED = ['(fry']\n")
    with pytest.raises(UserError, match="asked_states.toml"):
        load_asked_states(tmp_path)


def test_domain_check_reports_a_goal_example_that_leaves_out_a_state_its_instruction_asks_for(tmp_path: Path):
    from smartllm_local.planner.prompting.example_check import check_goal_examples

    copy = tmp_path / "household"
    shutil.copytree(load_domain("household").folder, copy)
    (copy / "prompts" / "goal" / "chop_and_bin.txt").write_text("Apple in GarbageCan\n")  # "Chop up the lettuce..."
    problems = check_goal_examples(load_domain(str(copy)))[1]
    assert len(problems) == 1 and "chop_and_bin.txt: states no thing in a state its instruction asks for" in \
        problems[0] and "SLICED" in problems[0]
