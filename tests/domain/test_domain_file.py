"""Domain files: the patrol domain loads as written, and every kind of mistake is one error at its line."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from smartllm_local.domain import DomainError, builtin_domains, load_domain, starter_domain
from smartllm_local.errors import CatalogueError, UserError
from smartllm_local.worlds import with_catalogue

PATROL = load_domain("patrol")
STARTER = (starter_domain() / "domain.toml").read_text(encoding="utf-8")


def test_builtin_domains_are_household_and_patrol():
    assert builtin_domains() == ["household", "patrol"]  # the starter is not a domain to plan in


def test_patrol_holds_the_papers_skills_and_a_mixed_team():
    assert list(PATROL.catalogue.skills) == ["GoToLocation", "ClickPicture", "Patrol"]
    assert PATROL.effects == {"GoToLocation": "move", "ClickPicture": "photograph", "Patrol": "patrol"}
    assert PATROL.pools == {"Patrol": "visibility_area"}
    kinds = {r.name: r.kind for r in PATROL.catalogue.robots.values()}
    assert kinds["drone1"] == "aerial" and kinds["rover1"] == "ground"
    assert PATROL.catalogue.robots[1].capacity("visibility_area") == 1500
    assert PATROL.catalogue.robots[6].capacity("camera_range") == 0
    roof = PATROL.place("warehouseroof")  # names match case-insensitively, as in plans
    assert roof is not None and roof.kind == "region" and roof.reach == frozenset({"aerial"}) and roof.area == 500


def test_household_is_the_default_and_keeps_its_catalogue():
    household = load_domain()
    assert household.world == "ai2thor" and household.name == "household"
    assert "PickupObject" in household.catalogue.skills and 1 in household.catalogue.robots


def test_an_unknown_domain_names_the_known_ones():
    with pytest.raises(DomainError, match=r"no domain 'patrl'.*household, patrol.*did you mean patrol"):
        load_domain("patrl")


def write(tmp_path: Path, text: str) -> Path:
    (tmp_path / "domain.toml").write_text(text, encoding="utf-8")
    return tmp_path


def line_of(text: str, needle: str) -> int:
    return next(k for k, line in enumerate(text.splitlines(), start=1) if needle in line)


@pytest.mark.parametrize("old, new, needle, message", [
    # a robot with a skill the domain does not define: the robot's name line, and the fix
    ('skills = ["GoToLocation", "ClickPicture", "Patrol"]\nvisibility_area = 300',
     'skills = ["GoToLocation", "ClickPicture", "Patroll"]\nvisibility_area = 300',
     'name = "rover"', r"robot rover has skill 'Patroll', which the domain does not define; did you mean Patrol\?"),
    # an argument type with no entries: the skill's line
    ('[world.regions.Yard]\nat = [30, 20]\narea = 800\n', '',
     "[skills.Patrol]", r"skill Patrol takes a region, and the site has none: add a \[world.regions.NAME\] table"),
    # an unknown key in a skill
    ('effect = "photograph"\n', 'effect = "photograph"\nrange = 3\n',
     "range = 3", r"skill ClickPicture: unknown key 'range'"),
    # an unknown effect
    ('effect = "move"', 'effect = "fly"', "[skills.GoToLocation]", r"effect must be one of move, photograph, patrol"),
    # a patrol skill that pools nothing
    ('pools = "visibility_area"\n', '', "[skills.Patrol]", r"needs pools = the capacity"),
    # a robot missing a capacity
    ('visibility_area = 900\n', '', 'name = "drone"', r"robot drone: needs visibility_area = a number"),
    # a region without an area
    ('area = 800\n', '', "[world.regions.Yard]", r"Yard: a region needs area"),
    # a start that is not on the site
    ('start = "Dock"', 'start = "Harbour"', "start = ", r"start must name the site entry every robot starts at"),
    # a mistyped top-level key
    ('site = "yard"', 'sites = "yard"', "sites = ", r"unknown key 'sites'"),
    # the same id twice
    ('id = 2\n', 'id = 1\n', 'name = "rover"', r"robot rover: id 1 is used twice"),
    # a robot without a kind (what a place's reach names)
    ('kind = "ground"\n', '', 'name = "rover"', r"robot rover: kind must be a word such as \"aerial\""),
])
def test_a_mistake_is_reported_at_its_line_with_the_fix(tmp_path, old, new, needle, message):
    assert_one_problem_at(tmp_path, STARTER, old, new, needle, message)


def assert_one_problem_at(tmp_path: Path, original: str, old: str, new: str, needle: str, message: str) -> None:
    """``original`` with ``old`` made ``new`` is one problem, at the line holding ``needle``, matching ``message``."""
    assert old in original, old
    text = original.replace(old, new, 1)
    folder = write(tmp_path, text)
    with pytest.raises(DomainError) as caught:
        load_domain(folder)
    problems = str(caught.value).splitlines()
    assert len(problems) == 1, problems
    match = re.match(rf"^{re.escape(str(folder / 'domain.toml'))}:(\d+): (.+)$", problems[0])
    assert match, problems[0]
    assert int(match.group(1)) == line_of(text, needle), (problems[0], needle)
    assert re.search(message, match.group(2)), match.group(2)


def test_every_problem_is_reported_at_once(tmp_path):
    text = STARTER.replace('effect = "move"', 'effect = "fly"').replace('start = "Dock"', 'start = "Nowhere"')
    with pytest.raises(DomainError) as caught:
        load_domain(write(tmp_path, text))
    assert len(str(caught.value).splitlines()) == 2  # the robots' skill is not reported again as undefined
    assert "effect must be one of" in str(caught.value) and "start must name" in str(caught.value)


def test_invalid_toml_is_one_error_naming_the_file(tmp_path):
    with pytest.raises(DomainError, match=r"domain.toml: not valid TOML: .*line 1"):
        load_domain(write(tmp_path, "name = \n"))


def test_a_team_from_a_domain_checks_its_ids():
    with pytest.raises(CatalogueError, match="unknown robot id"):
        PATROL.catalogue.team([1, 99])


# ------------------------------------------------------------------- AI2-THOR domains (household's form)

HOUSEHOLD_FILE = (load_domain().folder / "domain.toml").read_text(encoding="utf-8")


def test_household_is_a_domain_folder_with_smartllms_skills_and_robots():
    household = load_domain("household")
    assert household.folder.name == "household" and household.world == "ai2thor"
    assert [p.name for p in household.task_files()] == ["tasks.jsonl", "few_skills.jsonl", "infeasible.jsonl"]
    skills = household.catalogue.skills
    assert len(skills) == 14 and skills["SwitchOn"].action == "ToggleObjectOn" and skills["GoToObject"].action == ""
    assert skills["PutObject"].arguments == ("pickupable", "receptacle") and skills["ThrowObject"].required == 1
    robots = household.catalogue.robots
    assert len(robots) == 30 and robots[7].mass_capacity == 0.08 and "CleanObject" in robots[29].skills
    assert robots[24].describe() == "robot24 (skills: GoToObject, SwitchOff, SwitchOn; carries up to 100 kg)"


@pytest.mark.parametrize("old, new, needle, message", [
    ('action = "PickupObject"', 'action = "Grab"', "[skills.PickupObject]",
     r"skill PickupObject: action must be one of the AI2-THOR actions .*PickupObject"),
    ('arguments = ["openable"]\ndescription = "open', 'arguments = ["opennable"]\ndescription = "open',
     "[skills.OpenObject]", r"skill OpenObject: arguments must list 1 or 2 affordances"),
    ('arguments = ["toggleable"]\ndescription = "switch on', 'arguments = [["toggleable"]]\ndescription = "switch on',
     "[skills.SwitchOn]", r"skill SwitchOn: arguments must list 1 or 2 affordances"),
    ('action = "BreakObject"', 'action = ["BreakObject"]', "[skills.BreakObject]",
     r"skill BreakObject: action must be one of the AI2-THOR actions"),
    ('effect = "move"\narguments', 'effect = "patrol"\narguments', "[skills.GoToObject]",
     r'moves \(effect = "move"\) or names an action'),
    ('required = 1\n', 'required = 3\n', "[skills.ThrowObject]", r"required is how many arguments every call gives"),
    ('mass_capacity = 0.08\n', '', 'name = "robot7"', r"robot robot7: needs mass_capacity = a number"),
    ('name = "robot3"\n', 'name = "robot3"\nkind = "ground"\n', 'name = "robot3"', r"robot robot3: unknown key 'kind'"),
    ('world = "ai2thor"\n', 'world = "ai2thor"\nstart = "Kitchen"\n', "start = ",
     r"unknown key 'start'; an AI2-THOR domain file has"),
    ('skills = ["GoToObject", "CleanObject", "PickupObject"', 'skills = ["GoToObject", "CleanObjekt", "PickupObject"',
     'name = "robot30"', r"robot robot30 has skill 'CleanObjekt'.*did you mean CleanObject"),
])
def test_a_mistake_in_an_ai2thor_domain_is_reported_at_its_line(tmp_path, old, new, needle, message):
    assert_one_problem_at(tmp_path, HOUSEHOLD_FILE, old, new, needle, message)


def test_a_world_that_is_neither_ai2thor_nor_a_site_says_what_it_may_be(tmp_path):
    with pytest.raises(DomainError, match=r'needs world = "ai2thor" .* or a site'):
        load_domain(write(tmp_path, HOUSEHOLD_FILE.replace('world = "ai2thor"', 'world = "thor"')))


def test_a_json_catalogue_gives_an_ai2thor_domain_other_robots(tmp_path):
    path = tmp_path / "robots.json"
    path.write_text(json.dumps({
        "robots": [{"id": 1, "name": "arm", "skills": ["GoToObject", "Grab", "PutObject"], "mass_capacity": 2}],
        "skills": [{"name": "Grab", "action": "PickupObject", "arguments": ["pickupable"]}]}))
    domain = with_catalogue(load_domain("household"), path)
    assert list(domain.catalogue.robots) == [1] and domain.catalogue.robots[1].mass_capacity == 2
    assert domain.catalogue.skills["Grab"].action == "PickupObject" and "SwitchOn" in domain.catalogue.skills
    assert domain.task_files() == load_domain().task_files()  # the rest of the domain is household's
    path.write_text(json.dumps({"robots": [{"id": 1, "skills": ["Fly"], "mass_capacity": 1}]}))
    with pytest.raises(CatalogueError, match=r"robots\[0\]: unknown skill\(s\) \['Fly'\]"):
        with_catalogue(load_domain("household"), path)
    for skill in ({"name": "Grab", "action": ["PickupObject"]}, {"name": "Grab", "action": "PickupObject",
                                                                 "arguments": [["pickupable"]]}):
        path.write_text(json.dumps({"robots": [], "skills": [skill]}))
        with pytest.raises(CatalogueError, match=r"skills\[0\]: skill Grab: (action|arguments) must"):
            with_catalogue(load_domain("household"), path)


# ------------------------------------------------------------------- any value in any key: an error, never a crash


def _toml(value: Any) -> str:
    """A value as TOML text (JSON's string escapes are TOML's basic-string escapes)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if value != value else ("inf" if value > 0 else "-inf")
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, list):
        return "[" + ", ".join(map(_toml, value)) + "]"
    return "{" + ", ".join(f"{key} = {_toml(item)}" for key, item in value.items()) + "}"


_VALUES = st.recursive(
    st.one_of(st.integers(-3, 5000), st.floats(), st.booleans(), st.text(max_size=8),
              st.sampled_from(["move", "patrol", "ai2thor", "PickupObject", "pickupable", "Dock", "GoToLocation"])),
    lambda inner: st.one_of(st.lists(inner, max_size=3),
                            st.dictionaries(st.from_regex(r"[a-z]{1,6}", fullmatch=True), inner, max_size=3)),
    max_leaves=6)


@pytest.mark.parametrize("text", [STARTER, HOUSEHOLD_FILE], ids=["site", "ai2thor"])
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_any_value_in_any_key_is_a_clear_error_or_a_domain(tmp_path, text, data):
    """Whatever value a key is given (a list for a word, a table for a number, NaN ...), reading the file
    gives a domain or a DomainError naming the problem: never another exception."""
    lines = text.splitlines()
    keyed = [k for k, line in enumerate(lines) if re.match(r"^\w+ = ", line)]
    k = data.draw(st.sampled_from(keyed))
    key = lines[k].split(" = ")[0]
    lines[k] = f"{key} = {_toml(data.draw(_VALUES))}"
    (tmp_path / "domain.toml").write_text("\n".join(lines) + "\n", encoding="utf-8")
    try:
        load_domain(tmp_path)
    except UserError as exc:
        assert str(exc).startswith(str(tmp_path)) or "domain file" in str(exc), str(exc)
