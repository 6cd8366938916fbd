"""Real round trips: the unmodified ai2thor 5.0.0 Controller driving the stand-in process."""

from __future__ import annotations

import contextlib
import json
import os
import random
import shutil
import signal
import sys
import textwrap
import time
from pathlib import Path

import msgpack
import pytest
from ai2thor.controller import Controller
from ai2thor.server import MultiAgentEvent

from smartllm_local.errors import SceneDataError, UnknownFloorPlanError, UserError, WorldError
from smartllm_local.world import scenes
from smartllm_local.world.controller import open_controller, stand_in_command
from smartllm_local.world.navigation import Box
from smartllm_local.world.thor_server import ThorStandIn


def _object(event, object_type):
    return next(o for o in event.metadata["objects"] if o["objectType"] == object_type)


def _nearest(positions, obj):
    box = Box.of(obj)
    return min(positions, key=lambda p: (box.distance(p["x"], p["z"]), p["x"], p["z"]))


def test_single_agent_round_trip_through_the_console_script():
    """The Controller starts smartllm-thor-server exactly as it starts a Unity build."""
    script = shutil.which("smartllm-thor-server") or str(Path(sys.executable).with_name("smartllm-thor-server"))
    controller = Controller(local_executable_path=script, scene="FloorPlan6", x_display=":0", server_timeout=10)
    try:
        event = controller.last_event
        assert event.metadata["sceneName"] == "FloorPlan6_physics"
        assert len(event.metadata["objects"]) == 68
        apple = _object(event, "Apple")
        positions = controller.step(action="GetReachablePositions").metadata["actionReturn"]
        assert controller.step(action="Teleport", position=_nearest(positions, apple))
        event = controller.step(action="PickupObject", objectId=apple["objectId"])
        assert event.metadata["lastActionSuccess"], event.metadata["errorMessage"]
        assert event.metadata["inventoryObjects"] == [{"objectId": apple["objectId"], "objectType": "Apple"}]
        assert _object(event, "Apple")["isPickedUp"]
    finally:
        controller.stop()


def test_four_agents_each_have_their_own_view():
    controller = open_controller("FloorPlan15", agent_count=4)
    try:
        event = controller.last_event
        assert isinstance(event, MultiAgentEvent) and len(event.events) == 4
        starts = {(e.metadata["agent"]["position"]["x"], e.metadata["agent"]["position"]["z"]) for e in event.events}
        assert len(starts) == 4
        positions = controller.step(action="GetReachablePositions", agentId=2).metadata["actionReturn"]
        targets = ["Apple", "Tomato", "Bread", "Potato"]
        for agent_id, kind in enumerate(targets):
            obj = _object(controller.last_event, kind)
            taken = {(e.metadata["agent"]["position"]["x"], e.metadata["agent"]["position"]["z"])
                     for i, e in enumerate(controller.last_event.events) if i != agent_id}
            free = [p for p in positions if (p["x"], p["z"]) not in taken]
            controller.step(action="Teleport", position=_nearest(free, obj), agentId=agent_id)
            event = controller.step(action="PickupObject", objectId=obj["objectId"], agentId=agent_id)
            assert event.metadata["lastActionSuccess"], event.metadata["errorMessage"]
        for agent_id, kind in enumerate(targets):
            view = event.events[agent_id].metadata
            assert view["inventoryObjects"][0]["objectType"] == kind
            assert all(o["isPickedUp"] for o in view["objects"] if o["objectType"] in targets)
            held = next(o for o in view["objects"] if o["objectType"] == kind)
            assert held["visible"], "an agent sees what it holds"
        event = controller.step(action="PickupObject", objectId=_object(event, "Apple")["objectId"], agentId=3)
        assert not event.metadata["lastActionSuccess"]
        assert event.metadata["errorMessage"]
    finally:
        controller.stop()


def test_errors_come_back_as_ai2thor_does():
    controller = open_controller(6)
    try:
        event = controller.step(action="OpenObject", objectId="Fridge|+99.00|+00.00|+00.00")
        assert not event.metadata["lastActionSuccess"]
        assert "Object ID appears to be invalid" in event.metadata["errorMessage"]
        with pytest.raises(ValueError, match="Invalid action"):
            controller.step(action="Levitate")
        with pytest.raises(ValueError, match="requires objectId"):
            controller.step(action="PickupObject")
        assert controller.step(action="Pass").metadata["lastActionSuccess"], "the session survives errors"
    finally:
        controller.stop()


def test_a_contextual_rule_through_the_controller():
    controller = open_controller(6)
    try:
        objects = {o["objectType"]: o for o in controller.last_event.metadata["objects"]}
        for step in [
            dict(action="PickupObject", objectId=objects["Potato"]["objectId"]),
            dict(action="OpenObject", objectId=objects["Microwave"]["objectId"]),
            dict(action="PutObject", objectId=objects["Microwave"]["objectId"]),
            dict(action="CloseObject", objectId=objects["Microwave"]["objectId"]),
            dict(action="ToggleObjectOn", objectId=objects["Microwave"]["objectId"]),
        ]:
            event = controller.step(forceAction=True, **step)
            assert event.metadata["lastActionSuccess"], event.metadata["errorMessage"]
        potato = _object(event, "Potato")
        assert potato["temperature"] == "Hot" and potato["isCooked"]
        assert potato["parentReceptacles"] == [objects["Microwave"]["objectId"]]
    finally:
        controller.stop()


def test_slice_object_needs_no_knife_in_hand_as_in_unity():
    """Unity's SliceObject does not check what the agent holds; the knife is the executor's rule."""
    controller = open_controller(6)
    try:
        bread = _object(controller.last_event, "Bread")["objectId"]
        event = controller.step(action="SliceObject", objectId=bread, forceAction=True)
        assert event.metadata["lastActionSuccess"], event.metadata["errorMessage"]
        assert event.metadata["inventoryObjects"] == []
        assert _object(event, "Bread")["isSliced"]
        assert "BreadSliced" in {o["objectType"] for o in event.metadata["objects"]}
    finally:
        controller.stop()


def test_reset_restores_the_scene():
    controller = open_controller(6, agent_count=2)
    try:
        light = _object(controller.last_event, "LightSwitch")
        controller.step(action="ToggleObjectOff", objectId=light["objectId"], forceAction=True)
        assert not _object(controller.last_event, "LightSwitch")["isToggled"]
        event = controller.reset("FloorPlan6")
        assert _object(event, "LightSwitch")["isToggled"]
        assert len(event.events) == 2, "reset keeps the Initialize parameters"
    finally:
        controller.stop()


def _slice_bread_on_the_stool(controller):
    """Move the Bread to a Stool, slice it there, and say where its slices lie."""
    bread = _object(controller.last_event, "Bread")["objectId"]
    stool = _object(controller.last_event, "Stool")["objectId"]
    for step in [dict(action="PickupObject", objectId=bread), dict(action="PutObject", objectId=stool),
                 dict(action="SliceObject", objectId=bread)]:
        event = controller.step(forceAction=True, **step)
        assert event.metadata["lastActionSuccess"], event.metadata["errorMessage"]
    return [o["parentReceptacles"] for o in event.metadata["objects"] if o["objectType"] == "BreadSliced"]


def test_slices_after_a_reset_are_reported_where_they_were_cut():
    """A Controller reset and reused on the same floor plan reports the new run's slices, not an earlier run's."""
    reused = open_controller(6)
    try:
        bread = _object(reused.last_event, "Bread")["objectId"]
        assert reused.step(action="SliceObject", objectId=bread, forceAction=True).metadata["lastActionSuccess"]
        reused.reset("FloorPlan6")
        after_reset = _slice_bread_on_the_stool(reused)
    finally:
        reused.stop()
    fresh = open_controller(6)
    try:
        expected = _slice_bread_on_the_stool(fresh)
    finally:
        fresh.stop()
    assert expected and all(parents == [_object(fresh.last_event, "Stool")["objectId"]] for parents in expected)
    assert after_reset == expected


def test_every_floor_plan_is_served_to_a_two_agent_team():
    controller = open_controller(1, agent_count=2)
    try:
        for plan in scenes.all_floor_plans():
            event = controller.reset(plan, agentCount=2)
            assert [e.metadata["lastActionSuccess"] for e in event.events] == [True, True], plan
            assert event.events[1].metadata["objects"], plan
    finally:
        controller.stop()


def test_patched_events_match_a_full_encoding():
    """Steps that change no object answer with METADATA_PATCH; the merged event must equal a full one."""
    rng = random.Random(7)
    controller = open_controller(6, agent_count=3)
    replay = ThorStandIn()
    replay.handle({"action": "Reset", "sceneName": "FloorPlan6_physics", "sequenceId": 0})
    replay.handle({"action": "Initialize", "agentCount": 3, "visibilityDistance": 1.5, "gridSize": 0.25})
    try:
        positions = controller.step(action="GetReachablePositions").metadata["actionReturn"]
        replay.handle({"action": "GetReachablePositions", "agentId": 0})
        ids = [o["objectId"] for o in controller.last_event.metadata["objects"]]
        for i in range(120):
            agent = rng.randrange(3)
            kind = rng.choice(["Teleport", "RotateLeft", "Pass", "PickupObject", "PutObject", "OpenObject", "LookDown",
                               "SetObjectFilter", "ResetObjectFilter"])
            step = {"action": kind, "agentId": agent}
            if kind == "Teleport":
                step["position"] = rng.choice(positions)
            elif kind in ("PickupObject", "PutObject", "OpenObject"):
                step["objectId"] = rng.choice(ids)
            elif kind == "SetObjectFilter":
                step["objectIds"] = rng.sample(ids, rng.randrange(0, 12))
            event = controller.step(dict(step))
            replay.handle(dict(step, sequenceId=i + 10))
            expected = msgpack.unpackb(replay.encoder.encode(replay.sim, active_agent=agent, sequence_id=0), raw=False)
            for a in range(3):
                got = event.events[a].metadata
                want = expected["agents"][a]
                assert got["objects"] == want["objects"], (i, step, a)
                assert got["agent"] == want["agent"]
                assert got["inventoryObjects"] == want["inventoryObjects"]
    finally:
        controller.stop()


def test_an_object_filter_narrows_one_agents_metadata_as_ai2thor_does():
    controller = open_controller(6, agent_count=2)
    try:
        every = {o["objectType"]: o["objectId"] for o in controller.last_event.metadata["objects"]}
        kept = [every["Bread"], every["Knife"], "Ghost|+0.00|+0.00|+0.00"]
        event = controller.step(action="SetObjectFilter", objectIds=kept, agentId=0)
        assert event.metadata["lastActionSuccess"]
        assert sorted(o["objectId"] for o in event.events[0].metadata["objects"]) == sorted(kept[:2]), \
            "unknown ids are ignored"
        assert len(event.events[1].metadata["objects"]) == 68, "the other agent still reports everything"
        for step in (dict(action="PickupObject", objectId=every["Knife"]),
                     dict(action="SliceObject", objectId=every["Bread"])):
            event = controller.step(forceAction=True, agentId=0, **step)
            assert event.metadata["lastActionSuccess"], event.metadata["errorMessage"]
        filtered = {o["objectType"] for o in event.events[0].metadata["objects"]}
        assert filtered == {"Bread", "Knife"}, "slices made after the filter was set stay out of it"
        assert "BreadSliced" in {o["objectType"] for o in event.events[1].metadata["objects"]}
        event = controller.step(action="ResetObjectFilter", agentId=0)
        assert "BreadSliced" in {o["objectType"] for o in event.events[0].metadata["objects"]}
        with pytest.raises(ValueError, match="requires objectIds"):
            controller.step(action="SetObjectFilter", agentId=1)
        with pytest.raises(ValueError, match="list of strings"):
            controller.step(action="SetObjectFilter", objectIds="Bread", agentId=1)
        assert len(controller.step(action="Pass", agentId=1).events[1].metadata["objects"]) > 68
    finally:
        controller.stop()


def test_bad_inputs_fail_before_starting_anything(tmp_path):
    with pytest.raises(UnknownFloorPlanError, match="FloorPlan201-230"):
        open_controller("FloorPlan999")
    with pytest.raises(UserError, match="not an executable file"):
        open_controller(6, build=tmp_path / "no-such-build")
    with pytest.raises(UserError, match="agent_count"):
        open_controller(6, agent_count=0)


def _fake_build(tmp_path: Path, body: str) -> Path:
    """An executable that poses as AI2-THOR and misbehaves as told."""
    script = tmp_path / "fake-thor"
    script.write_text(
        f"#!{sys.executable}\n"
        + textwrap.dedent(
            """
            import os, struct, sys, time, msgpack
            open(os.environ["PID_FILE"], "w").write(str(os.getpid()))
            def greet(out):
                agent = {"sceneName": "", "screenWidth": 300, "screenHeight": 300, "thirdPartyCameras": [],
                         "sequenceId": 0, "lastActionSuccess": True, "errorMessage": "", "errorCode": "",
                         "actionReturn": None}
                body = msgpack.packb({"agents": [agent], "thirdPartyCameras": [], "activeAgentId": 0, "sequenceId": 0})
                out.write(struct.pack("!BI", 1, len(body)) + body + struct.pack("!BI", 255, 0)); out.flush()
            """
        )
        + textwrap.dedent(body)
    )
    script.chmod(0o755)
    return script


def _assert_gone(pid_file: Path) -> None:
    pid = int(pid_file.read_text())
    deadline = time.monotonic() + 5
    while Path(f"/proc/{pid}").exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not Path(f"/proc/{pid}").exists(), f"process {pid} was left behind"


@pytest.fixture
def pid_file(tmp_path, monkeypatch):
    path = tmp_path / "pid"
    monkeypatch.setenv("PID_FILE", str(path))
    return path


def test_a_process_that_dies_at_start_fails_fast(tmp_path, pid_file):
    build = _fake_build(tmp_path, "sys.exit(3)\n")
    started = time.monotonic()
    with pytest.raises(WorldError, match="status 3"):
        open_controller(6, build=build, server_timeout=30)
    assert time.monotonic() - started < 10
    _assert_gone(pid_file)


def test_a_process_that_never_answers_times_out_and_is_stopped(tmp_path, pid_file):
    build = _fake_build(
        tmp_path,
        """
        out = open(os.environ["AI2THOR_FIFO_SERVER_PIPE_PATH"], "wb")
        greet(out)
        inp = open(os.environ["AI2THOR_FIFO_CLIENT_PIPE_PATH"], "rb")
        time.sleep(600)
        """,
    )
    started = time.monotonic()
    with pytest.raises(WorldError, match="did not answer"):
        open_controller(6, build=build, server_timeout=1.5)
    assert time.monotonic() - started < 20
    _assert_gone(pid_file)


def test_a_process_that_dies_after_greeting_fails_fast(tmp_path, pid_file):
    build = _fake_build(
        tmp_path,
        """
        out = open(os.environ["AI2THOR_FIFO_SERVER_PIPE_PATH"], "wb")
        greet(out)
        inp = open(os.environ["AI2THOR_FIFO_CLIENT_PIPE_PATH"], "rb")
        inp.read(5)
        sys.exit(5)
        """,
    )
    started = time.monotonic()
    with pytest.raises(WorldError, match="status 5"):
        open_controller(6, build=build, server_timeout=30)
    assert time.monotonic() - started < 10
    _assert_gone(pid_file)


def test_a_stand_in_killed_mid_session_fails_the_next_step_fast():
    controller = open_controller(6, agent_count=2)
    proc = controller.server.unity_proc
    os.kill(proc.pid, signal.SIGKILL)
    started = time.monotonic()
    with pytest.raises(WorldError, match="status -9"):
        controller.step(action="Pass")
    assert time.monotonic() - started < 5
    with pytest.raises(WorldError, match="stopped"):
        controller.step(action="Pass")
    assert proc.poll() is not None


def test_stopping_leaves_no_process_behind():
    controller = open_controller(6)
    proc = controller.server.unity_proc
    controller.stop()
    assert proc.poll() is not None


class _Hung(BaseException):
    """Raised by the alarm when a call that must end by itself did not (BaseException: nothing swallows it)."""


@contextlib.contextmanager
def _must_return_within(seconds: float):
    def ring(signum, frame):
        raise _Hung(f"still blocked after {seconds} s")

    previous = signal.signal(signal.SIGALRM, ring)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


@pytest.mark.parametrize("wrapped", [False, True], ids=["direct", "behind-a-shell-script"])
def test_a_process_that_never_opens_its_pipe_is_stopped_at_the_start_deadline(tmp_path, pid_file, wrapped):
    build = _fake_build(tmp_path, "time.sleep(600)\n")
    if wrapped:  # the shell stays as the parent of the sleeper, which must not be left behind
        wrapper = tmp_path / "run-thor.sh"
        wrapper.write_text(f"#!/bin/sh\n{build}\necho done\n")
        wrapper.chmod(0o755)
        build = wrapper
    started = time.monotonic()
    with _must_return_within(30), pytest.raises(WorldError, match=r"did not greet within 2(\.0)? s"):
        open_controller(6, build=build, server_timeout=1, server_start_timeout=2)
    assert time.monotonic() - started < 10
    _assert_gone(pid_file)


@pytest.mark.parametrize("then", ["time.sleep(600)", "sys.exit(4)"])
def test_a_process_that_greets_and_never_opens_the_action_pipe_fails(tmp_path, pid_file, then):
    build = _fake_build(
        tmp_path,
        f"""
        out = open(os.environ["AI2THOR_FIFO_SERVER_PIPE_PATH"], "wb")
        greet(out)
        {then}
        """,
    )
    started = time.monotonic()
    with _must_return_within(30), pytest.raises(WorldError, match="action pipe|status 4"):
        open_controller(6, build=build, server_timeout=1.5)
    assert time.monotonic() - started < 10, "after the greeting, server_timeout applies, not server_start_timeout"
    _assert_gone(pid_file)


def test_a_slow_start_within_the_deadline_succeeds(tmp_path):
    """The deadline only ends a start that is late, not one that is slow."""
    slow = tmp_path / "slow-thor"
    slow.write_text(f"#!/bin/sh\nsleep 1.5\nexec {stand_in_command()}\n")
    slow.chmod(0o755)
    controller = open_controller(6, build=slow, server_timeout=5, server_start_timeout=4)
    try:
        assert controller.step(action="Pass").metadata["lastActionSuccess"]
    finally:
        controller.stop()


def test_a_relative_build_path_is_run_from_the_current_folder(tmp_path, monkeypatch, pid_file):
    monkeypatch.chdir(tmp_path)
    _fake_build(tmp_path, "sys.exit(3)\n")
    with pytest.raises(WorldError, match="status 3"):
        open_controller(6, build="./fake-thor", server_timeout=30)
    _assert_gone(pid_file)
    monkeypatch.setenv("SMARTLLM_THOR_BUILD", "fake-thor")
    with pytest.raises(WorldError, match=f"{tmp_path}/fake-thor.*status 3"):
        open_controller(6, server_timeout=30)


@pytest.mark.parametrize(
    "content, why",
    [
        ("echo no interpreter line\n", "Exec format error"),
        ("#!/no/such/interpreter\n", "No such file"),
    ],
)
def test_a_build_that_cannot_be_executed_is_a_user_error(tmp_path, monkeypatch, content, why):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "bad-thor").write_text(content)
    (tmp_path / "bad-thor").chmod(0o755)
    with pytest.raises(UserError, match=why) as info:
        open_controller(6, build="bad-thor")
    assert not isinstance(info.value, WorldError)
    assert str(tmp_path / "bad-thor") in str(info.value) and "\n" not in str(info.value)


def _broken_procthor(root: Path, dump: str | None) -> Path:
    """A procthor package whose scene dump is absent (None) or holds ``dump``."""
    package = root / "procthor"
    (package / "databases").mkdir(parents=True)
    (package / "__init__.py").write_text("")
    if dump is not None:
        (package / "databases" / "ai2thor-object-metadata.json").write_text(dump)
    return root


@pytest.mark.parametrize("problem", ["not installed", "no dump", "corrupt dump", "wrong shape"])
def test_broken_scene_data_is_reported_before_the_stand_in_starts(tmp_path, monkeypatch, problem):
    monkeypatch.setenv("SMARTLLM_CACHE_DIR", str(tmp_path / "cache"))
    scenes._memo.clear()
    if problem == "not installed":
        monkeypatch.setattr(scenes.importlib.util, "find_spec", lambda name: None)
    else:
        dump = {"no dump": None, "corrupt dump": '{"kitchens": [', "wrong shape": json.dumps({"kitchens": []})}[problem]
        fake = _broken_procthor(tmp_path / "site", dump)
        monkeypatch.syspath_prepend(str(fake))
        monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(fake), os.environ.get("PYTHONPATH")])))
    with _must_return_within(60), pytest.raises(SceneDataError) as info:
        open_controller(6)
    message = str(info.value)
    assert "procthor==0.0.1.dev2" in message and "\n" not in message
