"""Things a sub-task's robot keeps in hand, put where a stated goal wants them by that sub-task
(:mod:`smartllm_local.planner.kept_in_hand`), in the dry-run world of the real floor plans."""

from __future__ import annotations

from smartllm_local.planner.kept_in_hand import put_kept_things
from smartllm_local.planner.pipeline import PlannerConfig
from smartllm_local.scoring import Condition
from smartllm_local.worlds import scene_objects

from .constraints.test_finish import _final_state, _met
from .constraints.test_repair import SKILLS
from .test_idle_steps import decomposed

#: FloorPlan415: the candle carried to the toilet and kept; the planner's last sub-task put the soap bar on the
#: counter (the candle was in another robot's hand).
CANDLE = ("def subtask1_carry_candle():\n    # take the candle\n    GoToObject('Candle')\n    PickupObject('Candle')\n"
          "    GoToObject('Toilet')\n\n"
          "subtask1_carry_candle()\n\n"
          "def subtask2_meet_goals():\n    # the goals left: SoapBar in CounterTop\n    GoToObject('SoapBar')\n"
          "    PickupObject('SoapBar')\n    GoToObject('CounterTop')\n    PutObject('SoapBar', 'CounterTop')\n\n"
          "subtask2_meet_goals()\n")
ON_COUNTER = [Condition("CounterTop", item="Candle"), Condition("CounterTop", item="SoapBar")]
#: FloorPlan6: the apple picked up and kept while another sub-task switches the light off.
APPLE = ("def subtask1_take_apple():\n    GoToObject('Apple')\n    PickupObject('Apple')\n\n"
         "def subtask2_switch_off_light():\n    GoToObject('LightSwitch')\n    SwitchOff('LightSwitch')\n\n"
         "t1 = threading.Thread(target=subtask1_take_apple)\nt2 = threading.Thread(target=subtask2_switch_off_light)\n"
         "t1.start()\nt2.start()\nt1.join()\nt2.join()\n")
APPLE_GOALS = [Condition("Fridge", item="Apple"), Condition("LightSwitch", state="OFF")]


def test_the_candle_kept_in_hand_is_put_on_the_counter_by_its_own_sub_task():
    dry, failed = _final_state(CANDLE, 415)
    assert not failed and not _met(dry, ON_COUNTER[:1]) and _met(dry, ON_COUNTER[1:])
    text, added = put_kept_things(CANDLE, scene_objects(415), SKILLS, ON_COUNTER)
    put = ["    # then put it where it goes: Candle in CounterTop\n", "    GoToObject('CounterTop')\n",
           "    PutObject('Candle', 'CounterTop')\n"]
    assert added == put
    assert text == CANDLE.replace("    GoToObject('Toilet')\n", "    GoToObject('Toilet')\n" + "".join(put))
    dry, failed = _final_state(text, 415)
    assert not failed and _met(dry, ON_COUNTER)


def test_a_shut_holder_is_opened_first_and_the_other_sub_task_is_left_as_it_was():
    text, added = put_kept_things(APPLE, scene_objects(6), SKILLS, APPLE_GOALS)
    assert [line.strip() for line in added[1:]] == [
        "GoToObject('Fridge')", "OpenObject('Fridge')", "PutObject('Apple', 'Fridge')"]
    assert text.replace("".join(added), "") == APPLE
    assert text.index("PutObject('Apple'") < text.index("def subtask2_switch_off_light")
    dry, failed = _final_state(text, 6)
    assert not failed and _met(dry, APPLE_GOALS)


def test_a_thing_kept_that_no_goal_puts_anywhere_or_no_goals_leave_the_text_as_it_was():
    for goals in (APPLE_GOALS[1:], [], [Condition("Fridge", item="Tomato")]):
        assert put_kept_things(APPLE, scene_objects(6), SKILLS, goals) == (APPLE, [])


def test_the_planner_hands_the_coalition_the_decomposition_with_the_kept_thing_put_away(monkeypatch):
    """The decomposition's record keeps the lines written; its output and parsed plan, which the coalition and the
    allocation read, have them; with --no-finish-goals the text is the model's."""
    task = ("Put the candle and the soap bar on the counter.", "FloorPlan415", [25, 30])
    goals = "Candle in CounterTop\nSoapBar in CounterTop\n"
    for finish in (True, False):
        record = decomposed(monkeypatch, CANDLE, PlannerConfig(finish_goals=finish), goals, task)
        puts = [step.objects for fn in record.plan.functions for step in fn.body
                if getattr(step, "skill", None) == "PutObject"]
        assert (("Candle", "CounterTop") in puts) is finish
        assert len(record.put_away) == (3 if finish else 0)


def test_the_summary_counts_the_lines_that_put_kept_things_away():
    from smartllm_local.benchmark.results import repairs_line

    lines = [{"tokens": {"decomposition": {"put_away": 3}}}, {"tokens": {"decomposition": {"put_away": 0}}}]
    assert repairs_line(lines).endswith("3 line(s) putting a thing kept in hand where it goes in 1 task(s)")


def test_each_thing_kept_is_put_away_by_its_own_sub_task_from_where_the_one_before_left_the_world():
    """FloorPlan6: two sub-tasks each end holding a thing for the fridge; the first opens it, the second finds it
    open (its steps planned from the text with the first's put away)."""
    kept = ("def subtask1_take_apple():\n    GoToObject('Apple')\n    PickupObject('Apple')\n\n"
            "def subtask2_take_tomato():\n    GoToObject('Tomato')\n    PickupObject('Tomato')\n\n"
            "subtask1_take_apple()\nsubtask2_take_tomato()\n")
    goals = [Condition("Fridge", item="Apple"), Condition("Fridge", item="Tomato")]
    text, added = put_kept_things(kept, scene_objects(6), SKILLS, goals)
    assert [line.strip() for line in added] == [
        "# then put it where it goes: Apple in Fridge", "GoToObject('Fridge')", "OpenObject('Fridge')",
        "PutObject('Apple', 'Fridge')",
        "# then put it where it goes: Tomato in Fridge", "GoToObject('Fridge')", "PutObject('Tomato', 'Fridge')"]
    assert text.index("PutObject('Apple'") < text.index("def subtask2_take_tomato") < text.index("PutObject('Tomato'")
    dry, failed = _final_state(text, 6)
    assert not failed and _met(dry, goals)
