"""The stages' prompts, assembled from the worked examples in a domain's prompts/ folder.

Prompts are Python source, as in SMART-LLM: the skills as an import line (in a
decomposition, each task's own team's), worked examples (each a task description
followed by its plan), then the new task. The examples come first, always in file order, and the task's own
details last: a :class:`Prompt` is the part shared by every task of a stage
(whose key/value state a backend evaluates once), for a decomposition the
scene's objects (shared by the tasks on one floor plan), and the task's own part.

Coalition and allocation share one prompt where the model's context holds it:
each example shows its coalition and then its allocated plan, and a task's
allocation goes on in the context its coalition left, so it evaluates only the
line that opens it. A shorter context gets the paper's two prompts.

Ablations (as in the paper): ``comments=False`` removes the comment lines
from the examples' code, ``summary=False`` removes the summary block of the
decompositions, and ``coalition=False`` drops stage 2 (stage 3 then works
from the decomposition and the robots alone).
"""

from __future__ import annotations

import json
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ...domain import load_domain
from ...errors import UserError
from ...robots import Catalogue, Robot
from ...scene import SceneObjects
from ...skills import SkillSet
from ..constraints.coalition import LINE as COALITION_LINE

STAGES = ("decomposition", "coalition", "allocation")
DEFAULT_EXAMPLE_COUNTS = {"decomposition": 5, "coalition": 5, "allocation": 4}
_QUOTED = re.compile(r"'([A-Za-z]+)'")
_CALLED = re.compile(r"\b([A-Z]\w*)\(")


@dataclass(frozen=True)
class Example:
    name: str
    instruction: str
    floor_plan: int | str  # an iTHOR floor plan, or a site domain's site
    robots: tuple[int, ...]
    goals: tuple[dict[str, Any], ...]
    trans: int
    max_trans: int
    feasible: bool
    stages: tuple[str, ...]
    decomposition: str
    coalition: str | None
    allocation: str | None

    def object_types(self) -> list[str]:
        """The object types its plan mentions, in order of appearance."""
        return list(dict.fromkeys(_QUOTED.findall(self.decomposition)))


@dataclass(frozen=True)
class PromptOptions:
    comments: bool = True
    summary: bool = True
    coalition: bool = True
    example_counts: dict[str, int] = field(default_factory=lambda: dict(DEFAULT_EXAMPLE_COUNTS))


def load_examples(folder: Path | None = None) -> list[Example]:
    """The worked examples in ``folder`` (default: the household domain's), in the order examples.json lists them."""
    folder = folder or load_domain().prompts_dir()
    try:
        meta = json.loads((folder / "examples.json").read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise UserError(f"cannot read the prompt examples in {folder}: {exc}") from exc
    examples = []
    for entry in meta["examples"]:
        name = entry["name"]

        def read(stage: str, suffix: str, required: bool) -> str | None:
            path = folder / stage / f"{name}{suffix}"
            if not path.is_file():
                if required:
                    raise UserError(f"prompt example {name} lacks {path}")
                return None
            return path.read_text(encoding="utf-8")

        stages = tuple(entry["stages"])
        examples.append(Example(
            name=name, instruction=entry["instruction"], floor_plan=entry["floor_plan"],
            robots=tuple(entry["robots"]), goals=tuple(entry["goals"]), trans=entry["trans"],
            max_trans=entry["max_trans"], feasible=entry.get("feasible", True), stages=stages,
            decomposition=read("decomposition", ".py", True) or "",
            coalition=read("coalition", ".txt", "coalition" in stages),
            allocation=read("allocation", ".py", "allocation" in stages),
        ))
    return examples


@dataclass(frozen=True)
class Prompt:
    """A stage's prompt in parts: prefixes shared by ever fewer prompts, then the task's own text.

    The first part (the introduction and examples) begins every prompt of the stage that keeps as
    many examples; a decomposition's second part (the scene's object list) is also shared by every
    task on the same floor plan. A backend keeps the key/value state at the end of each prefix.
    Parts meet between words (``# Your`` and `` task``), where every tokenizer family splits, so
    that tokenized apart they give the tokens of the whole."""

    parts: tuple[str, ...]

    @property
    def text(self) -> str:
        return "".join(self.parts)


def examples_for(stage: str, examples: Sequence[Example], options: PromptOptions) -> list[Example]:
    chosen = [e for e in examples if stage in e.stages]
    return chosen[: options.example_counts.get(stage, len(chosen))]


# ------------------------------------------------------------------ transforms


def strip_comments(code: str) -> str:
    """The code without its comment lines (the summary block is kept: that is another ablation)."""
    lines = code.splitlines(keepends=True)
    body_started = False
    out = []
    for line in lines:
        if line.startswith("def ") or (line.strip() and not line.startswith("#")):
            body_started = True
        if body_started and line.lstrip().startswith("#"):
            continue
        out.append(line)
    return "".join(out)


def strip_summary(code: str) -> str:
    """The code without the summary block that precedes the first function."""
    lines = code.splitlines(keepends=True)
    first = next((i for i, line in enumerate(lines) if line.startswith("def ")), 0)
    return "".join(lines[first:])


def shape(code: str, options: PromptOptions) -> str:
    if not options.summary:
        code = strip_summary(code)
    if not options.comments:
        code = strip_comments(code)
    return code.rstrip("\n") + "\n"


THREADING_HEADER = "import threading\nimport time\n"


def skills_header(skills: SkillSet) -> str:
    return f"from skills import {', '.join(skills)}\n{THREADING_HEADER}"


def called_skills(code: str) -> frozenset[str]:
    """The names a plan's code calls: its skills, and such names as ``Thread`` that no robot has."""
    return frozenset(_CALLED.findall(code))


def robots_list(team: Sequence[Robot], plan: str) -> str:
    """The team, each robot with those of its skills that ``plan`` calls: all a coalition or an
    allocation weighs, where a robot's whole skill list (13 names for most household robots) would
    cost every task of the stage some 40 tokens per robot."""
    called = called_skills(plan)

    def describe(i: int, r: Robot) -> str:
        head = f"'name': 'robots[{i}]', 'id': {r.id}"
        skills = sorted(r.skills & called)
        if r.kind:  # a site domain's robot: its kind and capacities
            held = "".join(f", '{name}': {value:g}" for name, value in r.capacities)
            return f"{{{head}, 'kind': '{r.kind}', 'skills': {skills!r}{held}}}"
        return f"{{{head}, 'skills': {skills!r}, 'mass_capacity': {r.mass_capacity:g}}}"

    items = ",\n    ".join(describe(i, r) for i, r in enumerate(team))
    return f"robots = [\n    {items},\n]\n"


def _example_scene(example: Example, scene: SceneObjects) -> SceneObjects:
    """The scene an example was written for, in the task's world (a site domain's are all on its one site)."""
    return scene.world.scene(example.floor_plan)


# --------------------------------------------------------------------- stages

DECOMPOSITION_INTRO = """\
# Each task below is broken into sub-tasks: a summary of them, one function per
# sub-task, then the order they run in. Sub-tasks that do not depend on each other
# run in parallel threads; the others run one after another. A plan calls only the
# skills its task imports: those its robots have. A task that needs another skill,
# or more strength than its robots have together, is answered with one line that
# says what is missing: # INFEASIBLE: <why>.
"""

ALLOCATION_INTRO = """\
# Each plan below is rewritten for its robots: every function takes robot_list, every
# skill call names the robot (robot_list[0]) or the whole team (robot_list) that acts,
# and each sub-task is started with the robots the coalition chose for it.
"""


def team_import(skills: SkillSet, team: Sequence[Robot]) -> str:
    """The skills a team has, as the import line of its task (in the vocabulary's order)."""
    return f"from skills import {', '.join(s for s in skills if any(s in r.skills for r in team))}\n"


def decomposition_prompt(instruction: str, scene: SceneObjects, catalogue: Catalogue, team: Sequence[Robot],
                         examples: Sequence[Example], options: PromptOptions) -> Prompt:
    """The decomposition's prompt. Each task imports the skills of its own team (an example's, and the task's
    after its scene's objects, so the examples stay a prefix every task shares and the objects one every task
    on the floor plan shares): a plan can call only those."""
    skills = catalogue.skills
    parts = [THREADING_HEADER, "\n", DECOMPOSITION_INTRO]
    for k, ex in enumerate(examples, start=1):
        objects = _example_scene(ex, scene).python_list(ex.object_types())
        imports = team_import(skills, [catalogue.robots[i] for i in ex.robots])
        parts.append(f"\n# Example {k}\nobjects = {objects}\n{imports}# Task Description: {ex.instruction}\n")
        parts.append(shape(ex.decomposition, options))
    site = f" task\nobjects = {scene.python_list()}\nfrom"
    own = team_import(skills, team)[len("from"):]
    return Prompt(("".join(parts) + "\n# Your", site, f"{own}# Task Description: {instruction}\n"))


def plan_object_types(code: str, scene: SceneObjects) -> list[str]:
    return [t for t in dict.fromkeys(_QUOTED.findall(code)) if t in scene.masses]


ALLOCATION_GLUE = "# Allocated plan:\n"

TEAM_INTRO = """\
# Each plan is then rewritten for its robots: every function takes robot_list, every skill
# call names the robot (robot_list[0]) or the whole team (robot_list) that acts, and each
# sub-task is started with the robots its coalition chose.
"""


def coalition_prompt(decomposed: str, team: Sequence[Robot], scene: SceneObjects, skills: SkillSet,
                     catalogue: dict[int, Robot], examples: Sequence[Example], options: PromptOptions, *,
                     allocations: bool = True) -> Prompt:
    """The coalition's prompt. With ``allocations``, coalition and allocation share it: each example's
    coalition is followed by its allocated plan, and the task's allocation goes on from its coalition
    (:data:`ALLOCATION_GLUE` after the coalition the model wrote), so that it evaluates no prompt of
    its own. Decompositions appear without their line comments: a coalition weighs what each sub-task
    calls and lifts, not why each step is taken."""
    bare = PromptOptions(comments=False, summary=options.summary)
    rules = scene.world.coalition_rules()
    parts = [skills_header(skills), "\n", rules, TEAM_INTRO] if allocations else [rules]
    for k, ex in enumerate(examples, start=1):
        ex_team = [catalogue[i] for i in ex.robots]
        objects = _example_scene(ex, scene).python_list(ex.object_types())
        allocated = ""
        if allocations and "allocation" in ex.stages and ex.allocation:
            allocated = ALLOCATION_GLUE + shape(ex.allocation, PromptOptions(comments=options.comments, summary=True))
        parts.append(f"\n# Example {k}\n{shape(ex.decomposition, bare)}{robots_list(ex_team, ex.decomposition)}"
                     f"objects = {objects}\n# Coalition:\n{ex.coalition}{allocated}")
    objects = scene.python_list(plan_object_types(decomposed, scene))
    own = f" plan\n{shape(decomposed, bare)}{robots_list(team, decomposed)}objects = {objects}\n# Coalition:\n"
    return Prompt(("".join(parts) + "\n# Your", own))


def coalition_decisions(coalition: str) -> str:
    """Each coalition line cut to its decision, ``# SubTask k (<function>): <team>``; lines of
    another shape (a refusal, text written without the grammar) stay as they are."""
    return COALITION_LINE.sub(r"\1\4", coalition)


def allocation_prompt(decomposed: str, coalition: str | None, team: Sequence[Robot], skills: SkillSet,
                      catalogue: dict[int, Robot], examples: Sequence[Example], options: PromptOptions) -> Prompt:
    """The allocation's own prompt, where it does not share the coalition's (see :func:`coalition_prompt`).
    Decompositions appear without their line comments, and coalitions without their reasoning: the
    allocated code restates every line with its comment, and the allocation needs only whom each
    sub-task is started with."""
    bare = PromptOptions(comments=False, summary=options.summary)
    parts = [skills_header(skills), "\n", ALLOCATION_INTRO]
    for k, ex in enumerate(examples, start=1):
        ex_team = [catalogue[i] for i in ex.robots]
        coalition_part = f"# Coalition:\n{coalition_decisions(ex.coalition or '')}" if options.coalition else ""
        allocated = shape(ex.allocation or "", PromptOptions(comments=options.comments, summary=True))
        parts.append(f"\n# Example {k}\n{shape(ex.decomposition, bare)}{robots_list(ex_team, ex.decomposition)}"
                     f"{coalition_part}{ALLOCATION_GLUE}{allocated}")
    coalition_part = f"# Coalition:\n{coalition_decisions(coalition)}" if options.coalition and coalition else ""
    own = f" plan\n{shape(decomposed, bare)}{robots_list(team, decomposed)}{coalition_part}{ALLOCATION_GLUE}"
    return Prompt(("".join(parts) + "\n# Your", own))
