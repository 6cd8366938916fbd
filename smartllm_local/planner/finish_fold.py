"""The planner's last sub-task folded into one of the model's (its last, as a rule), so that meeting a forgotten
goal costs no transition.

The planner's last sub-task (:mod:`.constraints.finish`) is called after the model's orchestration: it begins
when every sub-task of the model has ended, one more transition by the paper's count. Where the team has no
robot left over, it cannot run beside them either: asked for a coffee and the apple in the fridge with two
robots, the 1.5B wrote the coffee's and the apple's sub-tasks, the planner put the mug into the coffee machine in a
third, and the plan met every goal with a transition the reference plan does not make (RU 0). Its steps are
written instead as the last steps of the model's last sub-task, after a comment naming the goals they meet, where
the dry run (a notional robot per sub-task, in the order written, as the world check runs a decomposition) shows
the same outcome: no call fails that did not, and the world ends in the same state as the goals see it (a room of
two CDs: the model's robot, standing elsewhere, takes the other one to the bin). The model's last sub-task
runs last in that order, so its robot takes the steps up from the state the planner planned them from, but for
where it stands and what it holds; a robot still holding something fails the first pickup, and the plan is left
as it was. An earlier sub-task takes the steps instead where the dry run ends the same with them there and the
last would then need a robot that another sub-task started with it needs, while the earlier would not: asked to
fry the potato and put the bread in the fridge, with one robot that switches but cannot open and one that opens
but cannot switch, the burner switched on in the bread's sub-task made it need both robots, and the potato's
sub-task waited for it. Only the model's own plan, the planner's lines and the team are read.
"""

from __future__ import annotations

from collections.abc import Sequence

from ..robots import Robot
from ..scene import SceneObjects
from ..skills import SkillSet
from .constraints.feasibility import EXACT_COALITIONS
from .constraints.finish import NAME
from .idle_steps import body_end, ends_as, function_name, text_outcome
from .in_turn import all_apart


def fold_finish(text: str, scene: SceneObjects, skills: SkillSet,
                team: Sequence[Robot] = ()) -> tuple[str, str | None]:
    """The decomposition with its last sub-task of the planner's written at the end of one of the model's, and that
    sub-task's name; the text as it was and None where it has no such sub-task or the dry run's outcome would
    differ wherever it went. The model's last sub-task takes it, unless with the ``team`` its sub-tasks started at
    once then have no teams apart while they would with it in another (the one with the steps needs a robot that
    another needs)."""
    lines = text.splitlines(keepends=True)
    defs = [n for n, line in enumerate(lines) if line.startswith("def ")]
    if len(defs) < 2 or not function_name(lines[defs[-1]]).endswith(f"_{NAME}"):
        return text, None
    last = defs[-1]
    body = body_end(lines, last)
    name = function_name(lines[last])
    if lines[last - 1] != "\n" or [line for line in lines[body:] if line.strip()] != [f"{name}()\n"]:
        return text, None
    checks_team = 2 <= len(team) <= EXACT_COALITIONS
    first = None  # the latest sub-task where the dry run ends the same, teams apart or not
    base = text_outcome(lines, scene, skills)
    for model in reversed(defs[:-1]):
        end = body_end(lines, model)
        folded = lines[:end] + lines[last + 1:body] + lines[end:last - 1]
        if not ends_as(base, folded, scene, skills):
            continue
        if not checks_team or all_apart(folded, skills, team, scene):
            return "".join(folded), function_name(lines[model])
        first = first or ("".join(folded), function_name(lines[model]))
    return first or (text, None)
