"""docs/conformance.md stays true to the schema and to what the firmware does:
every command is sent once to a running controller, in a state where it is
valid, and the status column must say "not implemented" exactly for the
commands that answer CMD_NOT_IMPLEMENTED_ERR."""
from __future__ import annotations

import re
from pathlib import Path

import can

from landscape._generated import landscape_pb2 as pb
from landscape.registry import COMMANDS, Command
from landscape.supervisor import Supervisor

ROOT = Path(__file__).resolve().parents[2]

# The probe drives these itself (they change the state it probes in).
SEQUENCE = {"connect", "disconnect", "lock", "release", "activate", "deactivate"}


def _rows() -> dict[str, list[str]]:
    rows = {}
    for line in (ROOT / "docs" / "conformance.md").read_text().splitlines():
        m = re.match(r"\| `(\w+)` \|(.*)\|$", line)
        if m:
            rows[m.group(1)] = [c.strip() for c in m.group(2).split("|")]
    return rows


def test_conformance_table_matches_the_schema() -> None:
    rows = _rows()
    names = {c.name for c in COMMANDS.values()}
    assert set(rows) == names
    for cmd in COMMANDS.values():
        section, states, blocking, owner, status, *_ = rows[cmd.name]
        assert states == "/".join(pb.State.Name(s) for s in cmd.states), cmd.name
        assert blocking.startswith("yes" if cmd.blocking else "no"), cmd.name
        assert owner == ("yes" if cmd.owner_only else "no"), cmd.name


def _probe(sup: Supervisor, cmd: Command, expect_state: str) -> int:
    """Send `cmd` with default (empty) arguments; the answer's code. The
    device must stay in `expect_state` (an empty request must not start anything)."""
    rv = sup.request(cmd.name, check=False, timeout_s=max(2.0, cmd.host_timeout_ms / 1000.0))
    assert rv.ret_code != pb.CMD_WRONG_STATE_ERR, f"{cmd.name} probed outside its states: {rv.ret_msg}"
    assert rv.ret_msg, f"{cmd.name} answered without a message"
    state = sup.get_motion_control_state().result["state"]
    assert state == expect_state, f"{cmd.name} (empty request) left the device in {state}"
    return rv.ret_code


def test_status_column_matches_what_the_firmware_answers(bus: can.BusABC) -> None:
    answers: dict[str, int] = {}
    with Supervisor(bus, client_name="docs") as sup:
        def probe_all(state: str) -> None:
            for cmd in COMMANDS.values():
                if cmd.name in SEQUENCE or cmd.name in answers:
                    continue
                if pb.State.Value(state) in cmd.states:
                    answers[cmd.name] = _probe(sup, cmd, state)

        probe_all("UNLOCKED")
        sup.lock()
        probe_all("LOCKED")
        sup.activate()
        probe_all("RESTING")
        # what is valid only while a motion runs or is paused
        rv = sup.move_relative("probe", [0.3, 0, 0, 0, 0, 0], speed_pct=5.0)
        assert rv.started
        for name, state in (("stopMotion", "PAUSED"), ("resumeMotion", "MOVING")):
            cmd = next(c for c in COMMANDS.values() if c.name == name)
            answers[name] = _probe(sup, cmd, state)
        sup.wait_complete(rv, timeout_s=30)
        sup.deactivate()
        sup.release()
    answers.update({name: pb.CMD_EXEC_OK for name in SEQUENCE})  # the sequence above ran them

    rows = _rows()
    assert set(answers) == {c.name for c in COMMANDS.values()}, "a command was not probed"
    for name, code in answers.items():
        status = rows[name][4]
        listed_missing = "not implemented" in status
        answered_missing = code == pb.CMD_NOT_IMPLEMENTED_ERR
        assert listed_missing == answered_missing, (
            f"{name}: docs/conformance.md says '{status}', the firmware answered {pb.RetCode.Name(code)}")
