"""The planner's last sub-task folded into the model's last one, so that meeting a forgotten goal costs no
transition.

The planner's last sub-task (:mod:`.constraints.finish`) is called after the model's orchestration: it begins
when every sub-task of the model has ended, one more transition by the paper's count. Where the team has no
robot left over, it cannot run beside them either: asked for a coffee and the apple in the fridge with two
robots, the 1.5B wrote the coffee's and the apple's sub-tasks, the planner put the mug into the coffee machine in a
third, and the plan met every goal with a transition the reference plan does not make (RU 0). Its steps are
written instead as the last steps of the model's last sub-task, after a comment naming the goals they meet, where
the dry run (a notional robot per sub-task, in the order written, as the world check runs a decomposition) shows
the same outcome: no call fails that did not, and the world ends in the same state. The model's last sub-task
runs last in that order, so its robot takes the steps up from the state the planner planned them from, but for
where it stands and what it holds; a robot still holding something fails the first pickup, and the plan is left
as it was. Only the model's own plan and the planner's lines are read.
"""

from __future__ import annotations

from collections.abc import Sequence

from ..scene import SceneObjects
from ..skills import SkillSet
from .constraints.finish import NAME
from .idle_steps import body_end, dry_outcome, function_name, skill_steps


def fold_finish(text: str, scene: SceneObjects, skills: SkillSet) -> tuple[str, str | None]:
    """The decomposition with its last sub-task of the planner's written at the end of the model's last sub-task,
    and that sub-task's name; the text as it was and None where it has no such sub-task or the dry run's outcome
    would differ."""
    lines = text.splitlines(keepends=True)
    defs = [n for n, line in enumerate(lines) if line.startswith("def ")]
    if len(defs) < 2 or not function_name(lines[defs[-1]]).endswith(f"_{NAME}"):
        return text, None
    last, model = defs[-1], defs[-2]
    body = body_end(lines, last)
    name = function_name(lines[last])
    if lines[last - 1] != "\n" or [line for line in lines[body:] if line.strip()] != [f"{name}()\n"]:
        return text, None
    end = body_end(lines, model)
    folded = lines[:end] + lines[last + 1:body] + lines[end:last - 1]
    if not _same_outcome(lines, folded, scene, skills):
        return text, None
    return "".join(folded), function_name(lines[model])


def _same_outcome(before: Sequence[str], after: Sequence[str], scene: SceneObjects, skills: SkillSet) -> bool:
    """Whether ``after`` fails no more calls than ``before`` in the dry run and leaves the world as it does."""
    old, new = skill_steps(before, skills), skill_steps(after, skills)
    if old is None or new is None:
        return False
    (old_failed, old_end), (new_failed, new_end) = dry_outcome(old, (), scene, skills), \
        dry_outcome(new, (), scene, skills)
    return len(new_failed) <= len(old_failed) and new_end == old_end
