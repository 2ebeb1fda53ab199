"""moveReact and comply against the simulated table (sim HAL): a guarded move
stops within 2 mm of first contact and says where and why; without contact it
stops at its maximum distance; comply holds the contact force within 20 % of
the target while it slides along the table."""
from __future__ import annotations

import math
import threading
import time

import pytest

from landscape import errors
from landscape._generated import landscape_pb2 as pb
from landscape.supervisor import notice_data
from sensor_fixtures import TABLE_TOP_M, Rig, rig  # noqa: F401 (fixture)


def _floats(text: str) -> list[float]:
    return [float(v) for v in text.split(",")]


def test_move_react_stops_within_2mm_of_first_contact(rig: Rig) -> None:
    sup = rig.sup
    rig.move_tip_to(0.5, -0.1, 0.2)
    # first contact: the flange face (no tool) reaches the table where the laser says
    laser_m = sup.get_sensor_reading("laser_standoff_sensor").result["current_data"][0]
    assert laser_m == pytest.approx(0.2 - TABLE_TOP_M, abs=1e-3)
    start_z = sup.get_robot_position().result["world_pose"][2]
    contact_z = start_z - laser_m
    rv = sup.move_react("force_sensor", [0.0, 0.0, 0.15], motion_speed_pct=15.0, thresholds=[0.0, 0.0, 5.0])
    assert rv.started
    n = sup.wait_complete(rv, timeout_s=20)
    d = notice_data(n)
    assert n.event_id == "moveReactComplete" and n.final
    assert d["reason"] == "threshold"
    pose = _floats(d["pose"])
    force = _floats(d["force"])
    assert len(pose) == 6 and len(force) == 6
    print(f"\nmoveReact at 15 %: first contact z {contact_z:.5f} m, stopped at z {pose[2]:.5f} m "
          f"({1000 * (contact_z - pose[2]):.3f} mm past contact), settled Fz {force[2]:.2f} N, "
          f"{d['trigger']} when it crossed")
    assert abs(pose[2] - contact_z) <= 0.002
    assert float(d["travelled"]) == pytest.approx(laser_m, abs=0.002)
    assert d["trigger"].startswith("Fz:") and float(d["trigger"][3:]) >= 5.0
    assert 0.0 < force[2] < 50.0  # pressing, but not with the overshoot's force
    measured = sup.get_robot_position().result["world_pose"]
    assert measured[:3] == pytest.approx(pose[:3], abs=2e-4)
    state = sup.get_motion_control_state().result
    assert state["state"] == "RESTING" and state["motion_control_state"] == "robot_at_rest"


def test_move_react_without_contact_stops_at_the_maximum_distance(rig: Rig) -> None:
    sup = rig.sup
    rig.move_tip_to(0.5, -0.1, 0.3)
    rv = sup.move_react("force_sensor", [0.0, 0.0, 0.05], motion_speed_pct=10.0, thresholds=[0.0, 0.0, 5.0])
    d = notice_data(sup.wait_complete(rv, timeout_s=20))
    assert d["reason"] == "max_distance"
    assert float(d["travelled"]) == pytest.approx(0.05, abs=1e-9)
    assert _floats(d["pose"])[2] == pytest.approx(0.25, abs=5e-4)
    assert "trigger" not in d


def test_move_react_on_the_laser_in_millimetres(rig: Rig) -> None:
    sup = rig.sup
    rig.move_tip_to(0.5, -0.1, 0.2)
    sup.set_units(linear=pb.MILLIMETERS, angular=pb.DEGREES)
    rv = sup.move_react("laser_standoff_sensor", [0.0, 0.0, 90.0], motion_speed_pct=10.0, thresholds=[30.0])
    d = notice_data(sup.wait_complete(rv, timeout_s=20))
    assert d["reason"] == "threshold"
    assert float(d["distance"]) == pytest.approx(30.0, abs=2.0)  # mm, back where it crossed 30 mm
    assert _floats(d["pose"])[2] == pytest.approx(1000 * (TABLE_TOP_M + 0.03), abs=2.0)
    assert float(d["travelled"]) == pytest.approx(70.0, abs=2.0)
    now = sup.get_sensor_reading("laser_standoff_sensor").result["current_data"][0]
    assert now == pytest.approx(30.0, abs=2.0)


def test_move_react_refusals_name_the_problem(rig: Rig) -> None:
    sup = rig.sup
    with pytest.raises(errors.UnsupportedError) as ei:
        sup.move_react("sonar", [0.0, 0.0, 0.05], thresholds=[1.0])
    assert "force_sensor, laser_standoff_sensor" in str(ei.value)
    with pytest.raises(errors.ParamError) as ei:
        sup.move_react("force_sensor", [0.0, 0.0, 0.05], thresholds=[0.0, 1.0, 2.0])
    assert "exactly one" in str(ei.value)
    with pytest.raises(errors.ParamError) as ei:
        sup.move_react("force_sensor", [0.0, 0.0, 0.05], thresholds=[0.0])
    assert "every threshold is 0" in str(ei.value)
    with pytest.raises(errors.ParamError) as ei:
        sup.move_react("force_sensor", [0.0, 0.0, 0.05, 0.0, 0.01, 0.0], thresholds=[1.0])
    assert "use comply" in str(ei.value)
    with pytest.raises(errors.ParamOutOfRangeError) as ei:
        sup.move_react("force_sensor", [0.0, 0.0, 2.0], thresholds=[0.0, 0.0, 5.0])
    assert "nothing moved" in str(ei.value)
    with pytest.raises(errors.ParamOutOfRangeError):
        sup.move_react("force_sensor", [0.0, 0.0, 0.05], thresholds=[0.0, 0.0, 5.0], envelope_max=[3.0])
    assert sup.get_motion_control_state().result["state"] == "RESTING"


def test_comply_holds_the_force_within_20_percent(rig: Rig) -> None:
    sup = rig.sup
    rig.move_tip_to(0.45, -0.1, TABLE_TOP_M + 0.015)
    target = 10.0
    rv = sup.comply("force_sensor", [0.0, 0.0, target], max_timeout_s=20.0, panic_stop_code=7,
                    max_travel=[0.15, 0.0, 0.0, 0.0, 0.0, 0.05], speed_pct=3.0)
    assert rv.started
    assert sup.get_motion_control_state().result["motion_control_state"] == "running_trajectory"
    samples: list[tuple[float, float]] = []
    done: dict[str, object] = {}

    def wait() -> None:
        try:
            done["n"] = sup.wait_complete(rv, timeout_s=30)
        except errors.LandscapeError as e:  # noqa: PERF203
            done["n"] = e

    t = threading.Thread(target=wait)
    t0 = time.monotonic()
    t.start()
    while t.is_alive():
        samples.append((time.monotonic() - t0, sup.get_sensor_reading("force_sensor").result["current_data"][2]))
        time.sleep(0.02)
    t.join()
    n = done["n"]
    assert not isinstance(n, Exception), n
    d = notice_data(n)
    assert n.event_id == "complyComplete" and d["reason"] == "max_travel"
    mean, lo, hi = float(d["fn_mean"]), float(d["fn_min"]), float(d["fn_max"])
    # sampled by the host once in contact (the travel starts then)
    in_contact = [f for _, f in samples if f > 0.5 * target]
    settled = in_contact[10:]
    print(f"\ncomply {target:g} N along the table: firmware over the travel mean {mean:.3f} N, "
          f"min {lo:.3f} N, max {hi:.3f} N ({100 * max(abs(lo - target), abs(hi - target)) / target:.1f} % worst); "
          f"host samples {len(settled)}: {min(settled):.3f}..{max(settled):.3f} N")
    assert abs(mean - target) <= 0.2 * target
    assert lo >= 0.8 * target and hi <= 1.2 * target
    assert len(settled) > 20
    assert all(abs(f - target) <= 0.2 * target for f in settled)
    pose = [float(v) for v in d["pose"].split(",")]
    assert pose[0] == pytest.approx(0.60, abs=1e-3)
    assert pose[2] == pytest.approx(TABLE_TOP_M - target / 5e4, abs=5e-4)


def test_comply_time_out_is_an_alarm(rig: Rig) -> None:
    sup = rig.sup
    rig.move_tip_to(0.45, -0.1, 0.3)
    rv = sup.comply("force_sensor", [0.0, 0.0, 10.0], max_timeout_s=0.5, panic_stop_code=3,
                    max_travel=[0.05, 0.0, 0.0, 0.0, 0.0, 0.05], speed_pct=3.0)
    with pytest.raises(errors.AlarmError) as ei:
        sup.wait_complete(rv, timeout_s=10)
    assert ei.value.notice.event_id == "complyTimeout"
    assert notice_data(ei.value.notice)["reason"] == "timeout"
    assert sup.get_motion_control_state().result["state"] == "RESTING"


def test_comply_refusals(rig: Rig) -> None:
    sup = rig.sup
    with pytest.raises(errors.ParamError) as ei:
        sup.comply("laser_standoff_sensor", [0.0, 0.0, 10.0], max_travel=[0.05, 0, 0, 0, 0, 0.05])
    assert "force sensor" in str(ei.value)
    with pytest.raises(errors.ParamError) as ei:
        sup.comply("force_sensor", [0.0, 0.0, 10.0], max_travel=[0.05, 0, 0.05, 0, 0, 0.05])
    assert "orthogonal" in str(ei.value)
    with pytest.raises(errors.ParamError) as ei:
        sup.comply("force_sensor", [5.0, 0.0, 10.0], max_travel=[0.05, 0, 0, 0, 0, 0.05])
    assert "along the compliance direction" in str(ei.value)
    # from MOVING: not one of its states (docs/conformance.md says why), said so
    rv = sup.move_relative("slow", [0.3, 0, 0, 0, 0, 0], speed_pct=5.0)
    with pytest.raises(errors.WrongStateError) as ei:
        sup.comply("force_sensor", [0.0, 0.0, 10.0], max_travel=[0.05, 0, 0, 0, 0, 0.05])
    assert "comply is valid in RESTING, the device is MOVING" in str(ei.value)
    sup.wait_complete(rv, timeout_s=20)


@pytest.mark.parametrize("field", ["gains", "envelope_min", "motion_speed_pct", "compliance_speed_pct"])
def test_move_react_refuses_a_number_that_is_not_finite_in_any_field(rig: Rig, field: str) -> None:
    """Found by tests/probe/probe.py: NaN in a field moveReact does not use started the move."""
    value: float | list[float] = math.nan if field.endswith("_pct") else [math.nan]
    with pytest.raises(errors.ParamError, match="values must be finite numbers"):
        rig.sup.move_react("force_sensor", [0.0, 0.0, -0.01], thresholds=[0.0, 0.0, 10.0], **{field: value})
    assert rig.sup.get_motion_control_state().result["state"] == "RESTING"


@pytest.mark.parametrize("field", ["envelope_min", "speed_pct", "compliance_speed_pct"])
def test_comply_refuses_a_number_that_is_not_finite_in_any_field(rig: Rig, field: str) -> None:
    value: float | list[float] = math.nan if field.endswith("_pct") else [math.nan]
    with pytest.raises(errors.ParamError, match="values must be finite numbers"):
        rig.sup.comply("force_sensor", [0.0, 0.0, 10.0], max_travel=[0.05, 0, 0, 0, 0, 0.05], **{field: value})
    assert rig.sup.get_motion_control_state().result["state"] == "RESTING"


@pytest.mark.parametrize("timeout_s", [1e308, 3600.5, 5e-324, 0.05, -1.0])
def test_comply_timeout_outside_its_range_is_refused(rig: Rig, timeout_s: float) -> None:
    """Found by tests/probe/probe.py: max_timeout_s 1e308 held a comply in free air at its range,
    MOVING, for as long as it said."""
    with pytest.raises(errors.ParamOutOfRangeError, match=r"allowed 0 \(30 s\) or \[0.1, 3600\] s"):
        rig.sup.comply("force_sensor", [0.0, 0.0, 10.0], max_timeout_s=timeout_s,
                       max_travel=[0.05, 0, 0, 0, 0, 0.05])
    assert rig.sup.get_motion_control_state().result["state"] == "RESTING"
