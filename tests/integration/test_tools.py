"""getTool/putTool/activateTool/deactivateTool/getEndEffectorState with the
sim world's tool rack: picking a tool changes the tool offset and the end
effector state, putting it back restores them; wrong tools are clear errors."""
from __future__ import annotations

import pytest

from landscape import errors
from sensor_fixtures import Rig, rig  # noqa: F401 (fixture)


def test_pick_use_and_put_back_a_tool(rig: Rig) -> None:
    sup = rig.sup
    assert sup.get_end_effector_state().result == {"current_ee": "none", "ee_state": "flange (no tool)"}
    assert sup.get_tool_offsets().result["offset"] == [0.0] * 6
    before = sup.get_robot_position().result["world_pose"]

    rv = sup.get_tool("gripper", timeout_s=60)
    assert rv.ok and "gripper" in rv.ret_msg
    assert sup.get_tool_offsets().result["offset"] == pytest.approx([0, 0, 0.12, 0, 0, 0], abs=1e-12)
    assert sup.get_end_effector_state().result == {"current_ee": "gripper", "ee_state": "bits=0x0"}
    st = sup.get_motion_control_state().result
    assert st["state"] == "RESTING" and st["motion_control_state"] == "robot_at_rest"
    # the approach point above the rack (flange 0.10 m above 0.35), tool tip 0.12 m further down
    tip = sup.get_robot_position().result["world_pose"]
    assert tip[:3] == pytest.approx([0.30, 0.50, 0.45 - 0.12], abs=1e-3)

    sup.activate_tool("gripper", 0x1)
    assert sup.get_end_effector_state().result["ee_state"] == "bits=0x1"
    sup.deactivate_tool("gripper", 0x1)
    assert sup.get_end_effector_state().result["ee_state"] == "bits=0x0"
    with pytest.raises(errors.ParamOutOfRangeError) as ei:
        sup.activate_tool("gripper", 0x2)
    assert "no such bits" in str(ei.value)
    with pytest.raises(errors.ParamError) as ei:
        sup.activate_tool("probe", 0x1)
    assert "the held tool is gripper" in str(ei.value)
    with pytest.raises(errors.GenericCommandError) as ei:
        sup.get_tool("probe", timeout_s=60)
    assert "put back gripper first" in str(ei.value)
    with pytest.raises(errors.ParamError) as ei:
        sup.put_tool("probe", timeout_s=60)
    assert "the held tool is gripper" in str(ei.value)

    sup.activate_tool("gripper", 0x1)
    rv = sup.put_tool("gripper", timeout_s=60)
    assert rv.ok
    assert sup.get_tool_offsets().result["offset"] == [0.0] * 6
    assert sup.get_end_effector_state().result == {"current_ee": "none", "ee_state": "flange (no tool)"}
    tip = sup.get_robot_position().result["world_pose"]
    assert tip[:3] == pytest.approx([0.30, 0.50, 0.45], abs=1e-3)
    assert before != tip


def test_unknown_tool_and_nothing_to_put_back(rig: Rig) -> None:
    sup = rig.sup
    with pytest.raises(errors.ParamError) as ei:
        sup.get_tool("hammer", timeout_s=60)
    assert "unknown tool 'hammer'" in str(ei.value) and "gripper, probe" in str(ei.value)
    with pytest.raises(errors.GenericCommandError) as ei:
        sup.put_tool("probe", timeout_s=60)
    assert "no tool is held" in str(ei.value)
    with pytest.raises(errors.ParamError):
        sup.activate_tool("none", 0x1)
    with pytest.raises(errors.WrongStateError):  # getTool moves the arm: RESTING only
        sup.deactivate()
        sup.get_tool("gripper", timeout_s=60)
