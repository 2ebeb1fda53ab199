"""The landscape CLI against the fake device (in-process via CliRunner, plus one real subprocess)."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner, Result

from fake_device import FakeDevice
from landscape import ls
from landscape.cli import cli

SRC = Path(__file__).resolve().parents[2] / "host_tools" / "src"


def run(channel: str, *args: str) -> Result:
    return CliRunner().invoke(cli, ["--interface", "virtual", "--channel", channel, *args])


def one_line_error(r: Result) -> str:
    assert r.exception is None or isinstance(r.exception, SystemExit), r.exception
    assert "Traceback" not in r.stderr and "Traceback" not in r.stdout
    lines = r.stderr.splitlines()
    assert len(lines) == 1, r.stderr
    return lines[0]


def test_text_output(channel: str, device: FakeDevice) -> None:
    r = run(channel, "get-motion-control-state")
    assert r.exit_code == 0, r.stderr
    assert r.stdout.splitlines() == [
        "get-motion-control-state: CMD_EXEC_OK", "  motion_control_state: robot_at_rest",
        "  control_mode: power_off", "  state: UNLOCKED", "  fault: ", "  owner: False"]
    assert device.sessions == {}  # the CLI disconnected on exit


def test_json_output_parses(channel: str, device: FakeDevice) -> None:
    from landscape.cli_core import LOCK_NOTE

    r = run(channel, "--json", "lock")
    assert r.exit_code == 0
    assert json.loads(r.stdout) == {"command": "lock", "ret_code": 0, "ret_name": "CMD_EXEC_OK", "ret_msg": "",
                                    "result": {}, "notices": [], "note": LOCK_NOTE}


def test_connect_prints_device_description(channel: str, device: FakeDevice) -> None:
    r = run(channel, "--json", "connect")
    out = json.loads(r.stdout)
    assert out["result"]["device_name"] == "fake" and out["result"]["joint_count"] == 6


def test_command_error_exit_3_one_line(channel: str, device: FakeDevice) -> None:
    r = run(channel, "release")
    assert r.exit_code == 3
    assert one_line_error(r).startswith("landscape: release: CMD_NOT_OWNER_ERR: lock first (")
    assert r.stdout == ""  # said once, on stderr (docs/host-tool.md "Errors and exit codes")


def test_non_blocking_waits_and_prints_notices(channel: str, device: FakeDevice, tmp_path: Path) -> None:
    script = tmp_path / "move.ls"
    script.write_text("# a move\nlock\n\nactivate\nmove-absolute p1 joint 0 -0.5 0 0 0 0 --speed-pct 20\n")
    r = run(channel, "run", str(script))
    assert r.exit_code == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[:4] == ["> lock", "lock: CMD_EXEC_OK", "> activate", "activate: CMD_EXEC_OK"]
    assert lines[4] == "> move-absolute p1 joint 0 -0.5 0 0 0 0 --speed-pct 20"
    assert lines[5] == "move-absolute: CMD_STARTED_OK"
    assert lines[6].startswith("  EVENT tag tag=p1 path= (ref 5)")
    assert lines[7].startswith("  EVENT_RSVP confirmMove point=p1 (ref 5) [rsvp 1: default 'continue'")
    assert lines[8] == "  EVENT moveAbsoluteComplete point=p1 reason=complete joints=0,-0.5,0,0,0,0 (ref 5) final"
    move = [q for q in device.requests if q.WhichOneof("cmd") == "move_absolute"][0]
    assert move.move_absolute == ls.MoveAbsoluteReq(point_name="p1", frame=ls.JOINT_FRAME,
                                                    values=[0, -0.5, 0, 0, 0, 0], speed_pct=20)
    assert [q.seq for q in device.requests] == [1, 2, 3, 4, 5, 6]  # one session for the whole file


def test_json_non_blocking_with_notices_and_alarm(channel: str, device: FakeDevice, tmp_path: Path) -> None:
    script = tmp_path / "alarm.ls"
    script.write_text("lock\nactivate\nmove-absolute far JOINT_FRAME 4 0 0 0 0 0\n")
    r = run(channel, "--json", "run", str(script))
    assert r.exit_code == 3
    objs = [json.loads(line) for line in r.stdout.splitlines()]
    assert [o["command"] for o in objs] == ["lock", "activate", "move-absolute"]
    assert [n["event_id"] for n in objs[2]["notices"]] == ["tag", "confirmMove", "moveAbsoluteFailed"]
    assert objs[2]["notices"][2]["kind"] == "ALARM" and objs[2]["notices"][2]["final"] is True
    assert "alarm.ls:3: move-absolute ended with alarm moveAbsoluteFailed" in r.stderr


def test_no_wait(channel: str, device: FakeDevice, tmp_path: Path) -> None:
    script = tmp_path / "nowait.ls"
    script.write_text("lock\nactivate\nmove-absolute p tool 0 0 0 0 0 0 --no-wait\n")
    r = run(channel, "run", str(script))
    assert r.exit_code == 0
    assert r.stdout.splitlines()[-1] == "move-absolute: CMD_STARTED_OK"


def test_run_stops_at_first_error(channel: str, device: FakeDevice, tmp_path: Path) -> None:
    script = tmp_path / "bad.ls"
    script.write_text("release\nlock\n")
    r = run(channel, "run", str(script))
    assert r.exit_code == 3
    assert [q.WhichOneof("cmd") for q in device.requests] == ["connect", "describe", "release", "disconnect"]
    assert r.stderr.splitlines()[0].startswith(f"{script}:1: release: CMD_NOT_OWNER_ERR")


def test_run_keep_going(channel: str, device: FakeDevice, tmp_path: Path) -> None:
    script = tmp_path / "bad.ls"
    script.write_text("release\nfly away\nmove-absolute p sideways 1\nrecord x.csv\nlock\n")
    r = run(channel, "run", "--keep-going", str(script))
    assert r.exit_code == 3
    assert [q.WhichOneof("cmd") for q in device.requests] == ["connect", "describe", "release", "lock", "disconnect"]
    err = r.stderr.splitlines()
    assert err[1] == f"{script}:2: unknown command 'fly' (`help` in the shell, landscape --help, lists them)"
    assert err[2].startswith(f"{script}:3: Invalid value for 'FRAME': 'sideways' is not a ReferenceFrame")
    assert err[3] == (f"{script}:4: 'record' runs on its own, not in a `run` file or the shell (it holds the "
                      f"terminal or the session): run `landscape record ...` in another terminal")
    assert r.stdout.splitlines()[-1] == "lock: CMD_EXEC_OK"


def test_run_all_ok_exit_0(channel: str, device: FakeDevice, tmp_path: Path) -> None:
    script = tmp_path / "ok.ls"
    script.write_text("lock   # take control\nget-motion-control-state\nrelease\n")
    r = run(channel, "run", str(script))
    assert r.exit_code == 0, r.stderr
    assert r.stdout.count("CMD_EXEC_OK") == 3 and "  owner: True" in r.stdout and r.stderr == ""
    assert device.owner is None


@pytest.mark.parametrize("args,code,start", [
    (["fly"], 2, "landscape: error: No such command 'fly'."),
    (["move-absolute", "p", "sideways"], 2, "landscape: error: Invalid value for 'FRAME': 'sideways'"),
    (["move-absolute", "p", "joint", "1", "x"], 2, "landscape: error: Invalid value for 'VALUES...': 'x'"),
    # a required argument is required: a bare move is a usage error, never sent to the device
    (["move-absolute", "p", "joint"], 2, "landscape: error: Missing argument 'VALUES...'"),
    (["move-absolute"], 2, "landscape: error: Missing argument '"),
    # an enum argument too (click 8.3 on takes an explicit default=None as a value, not as missing)
    (["move-absolute", "p"], 2, "landscape: error: Missing argument 'FRAME'"),
    (["get-digital-io"], 2, "landscape: error: Missing argument 'TYPE'"),
    (["set-speed", "--speed", "fast"], 2, "landscape: error: Invalid value for '--speed': 'fast'"),
    (["lock", "extra"], 2, "landscape: error: Got unexpected extra argument (extra)"),
])
def test_usage_errors_one_line_exit_2(channel: str, args: list[str], code: int, start: str) -> None:
    r = run(channel, *args)
    assert r.exit_code == code
    assert one_line_error(r).startswith(start)


def test_time_out_one_line_exit_4(channel: str) -> None:
    r = run(channel, "--timeout", "0.05", "lock")
    assert r.exit_code == 4
    assert one_line_error(r) == (
        f"landscape: no answer from the controller at address 0x10 on virtual:{channel} to connect "
        f"(seq 1, 3 tries of 0.05 s): is landscaped running on that channel with node address 0x10?")


def test_no_controller_on_a_pty_is_one_line_without_the_librarys_warnings() -> None:
    """can-isotp warns on its logger ("Reception of FlowControl timed out") while no one answers;
    without -v none of that reaches the terminal before the one error line."""
    master, slave = os.openpty()
    try:
        r = subprocess.run([str(Path(sys.executable).parent / "landscape"), "--interface", "slcan", "--channel",
                            os.ttyname(slave), "get-units"], capture_output=True, text=True, timeout=60)
    finally:
        os.close(master)
        os.close(slave)
    assert r.returncode == 4, r.stderr
    assert len(r.stderr.splitlines()) == 1 and "no answer from the controller" in r.stderr, r.stderr


def test_device_address_option(channel: str) -> None:
    r = run(channel, "--timeout", "0.05", "--device", "0x22", "lock")
    assert r.exit_code == 4 and "at address 0x22" in r.stderr
    r = run(channel, "--device", "0x123", "lock")
    assert r.exit_code == 2 and one_line_error(r).startswith("landscape: error: Invalid value for '--device'")


def test_version_mismatch_exit_5(channel: str, device: FakeDevice) -> None:
    device.schema_hash ^= 1
    r = run(channel, "lock")
    assert r.exit_code == 5
    assert one_line_error(r).startswith("landscape: version mismatch: host and firmware were built from "
                                        "different schemas")


def test_no_such_channel_subprocess(tmp_path: Path) -> None:
    env = dict(os.environ, PYTHONPATH=str(SRC))
    env.pop("CAN_INTERFACE", None)
    p = subprocess.run([sys.executable, "-m", "landscape", "--interface", "slcan", "--channel",
                        str(tmp_path / "nopty"), "lock"], capture_output=True, text=True, env=env, timeout=60)
    assert p.returncode == 4
    assert "Traceback" not in p.stderr and len(p.stderr.splitlines()) == 1
    assert p.stderr.startswith(f"landscape: cannot open CAN channel '{tmp_path / 'nopty'}' on interface 'slcan'")
    assert "is landscaped running with --link slcan:pty:PATH" in p.stderr


def test_shell_one_session_with_completion_names(channel: str, device: FakeDevice, tmp_path: Path) -> None:
    from prompt_toolkit.application import create_app_session
    from prompt_toolkit.input import create_pipe_input
    from prompt_toolkit.output import DummyOutput

    with create_pipe_input() as inp, create_app_session(input=inp, output=DummyOutput()):
        inp.send_text("lock\nfly\nrelease extra\nget-motion-control-state\nquit\n")
        r = CliRunner().invoke(cli, ["--interface", "virtual", "--channel", channel, "shell"],
                               env={"XDG_STATE_HOME": str(tmp_path)})
    assert r.exit_code == 0, r.stderr
    assert "lock: CMD_EXEC_OK" in r.stdout and "  owner: True" in r.stdout
    assert r.stderr.splitlines() == ["error: unknown command 'fly' (`help` in the shell, landscape --help, lists "
                                     "them)",
                                     "error: Got unexpected extra argument (extra)"]
    assert [q.seq for q in device.requests] == [1, 2, 3, 4, 5]  # connect, describe, then the lines
    assert (tmp_path / "landscape" / "history").read_text().count("\n+") == 5


def test_monitor_once_shows_telemetry(channel: str, device: FakeDevice) -> None:
    r = run(channel, "monitor", "--once")
    assert r.exit_code == 0, r.stderr
    assert "UNLOCKED" in r.stdout and "+0.5000 -0.2500" in r.stdout and "supervisors" in r.stdout
    # units are shown (rich took "[rad]" for markup and printed nothing)
    assert "joints (rad)" in r.stdout


def test_run_file_with_an_unclosed_quote_is_one_line(channel: str, device: FakeDevice, tmp_path: Path) -> None:
    script = tmp_path / "quote.ls"
    script.write_text('lock\nset-digital-io dio "unclosed\nrelease\n')
    r = run(channel, "run", str(script))
    assert r.exit_code == 2
    assert "Traceback" not in r.stderr
    assert r.stderr.splitlines()[0] == (f"{script}:2: cannot split the line into words (no closing quotation): "
                                        f"close the quote or escape it with a backslash")
    assert [q.WhichOneof("cmd") for q in device.requests] == ["connect", "describe", "lock", "disconnect"]


def test_shell_lines_never_end_the_shell(channel: str, device: FakeDevice, tmp_path: Path) -> None:
    from prompt_toolkit.application import create_app_session
    from prompt_toolkit.input import create_pipe_input
    from prompt_toolkit.output import DummyOutput

    with create_pipe_input() as inp, create_app_session(input=inp, output=DummyOutput()):
        inp.send_text('lock --help\nhelp set-speed\nhelp fly\nhelp\nset-digital-io dio "x\n'
                      'release extra\nrelease\nget-motion-control-state\nquit\n')
        r = CliRunner().invoke(cli, ["--interface", "virtual", "--channel", channel, "shell"],
                               env={"XDG_STATE_HOME": str(tmp_path)})
    assert r.exit_code == 0, r.stderr
    assert "Traceback" not in r.stdout + r.stderr
    assert "Usage: landscape lock [OPTIONS]" in r.stdout                     # CMD --help
    assert "Usage: landscape set-speed [OPTIONS] ATTRIBUTE" in r.stdout       # help CMD
    assert "\n  move-absolute " in r.stdout                                    # help: one line per command
    err = r.stderr.splitlines()
    assert err[:3] == [
        "error: no command 'fly' in the shell: `help` lists them",
        "error: cannot split the line into words (no closing quotation): close the quote or escape it "
        "with a backslash",
        "error: Got unexpected extra argument (extra)"], r.stderr
    assert len(err) == 4 and err[3].startswith("release: CMD_NOT_OWNER_ERR: "), r.stderr
    assert "get-motion-control-state: CMD_EXEC_OK" in r.stdout  # the shell went on to the end


def test_version_names_protocol_and_schema() -> None:
    from landscape.registry import PROTOCOL_VERSION, SCHEMA_HASH

    r = CliRunner().invoke(cli, ["--version"])
    assert r.exit_code == 0
    assert r.stdout.startswith("landscape ") and r.stdout.rstrip().endswith(
        f"(protocol {PROTOCOL_VERSION}, schema {SCHEMA_HASH:08X})")


def test_verbose_shows_requests_and_answers(channel: str, device: FakeDevice) -> None:
    r = run(channel, "-v", "lock")
    assert r.exit_code == 0, r.stderr
    assert "landscape.cli: -> lock {} (via bus)" in r.stderr
    assert "landscape.cli: <- lock seq 3 CMD_EXEC_OK {}" in r.stderr  # seq 1 was connect, 2 describe


def test_monitor_names_motion_and_mode_from_the_dbc() -> None:
    """st_motion and st_control_mode are shown by their DBC value-table names, the
    newest (5, robot_stopping) included; a value the table lacks shows as its number."""
    from rich.console import Console

    from landscape.cli import monitor_view

    def shown(motion: int, mode: int) -> str:
        console = Console(width=120, record=True)
        console.print(monitor_view({"STATUS": {"st_state": 0, "st_motion": motion, "st_control_mode": mode}},
                                   "t", []))
        return console.export_text()

    assert "robot_stopping" in shown(5, 1) and "power_on" in shown(5, 1)
    assert "robot_stopped_on_command" in shown(4, 0) and "power_off" in shown(4, 0)
    assert " 9 " in shown(9, 2) or "9\n" in shown(9, 2)


def test_shell_takes_lines_while_a_motion_runs(channel: str, device: FakeDevice, tmp_path: Path) -> None:
    """A motion returns to the prompt at once: a line typed meanwhile runs while the arm moves,
    and the motion's notices and end print as they arrive."""
    import threading
    import time

    from prompt_toolkit.application import create_app_session
    from prompt_toolkit.input import create_pipe_input
    from prompt_toolkit.output import DummyOutput

    device.move_time_s = 0.5
    with create_pipe_input() as inp, create_app_session(input=inp, output=DummyOutput()):
        inp.send_text("lock\nactivate\nmove-absolute p1 joint 0 -0.5 0 0 0 0\nget-motion-control-state\n")

        def quit_after_the_move() -> None:
            deadline = time.monotonic() + 20
            while time.monotonic() < deadline and not any(
                    q.WhichOneof("cmd") == "get_motion_control_state" for q in device.requests):
                time.sleep(0.02)
            while time.monotonic() < deadline and device.state == ls.MOVING:
                time.sleep(0.02)
            time.sleep(0.5)  # the final notice reaches the follower
            inp.send_text("quit\n")
        threading.Thread(target=quit_after_the_move, daemon=True).start()
        r = CliRunner().invoke(cli, ["--interface", "virtual", "--channel", channel, "shell"],
                               env={"XDG_STATE_HOME": str(tmp_path)})
    assert r.exit_code == 0, r.stderr
    out = r.stdout
    assert "move-absolute: CMD_STARTED_OK" in out and "the prompt is free" in out
    # the query ran while the move was under way, before its end was printed
    state = out.index("get-motion-control-state: CMD_EXEC_OK")
    assert "  state: MOVING" in out[state:]
    assert state < out.index("EVENT moveAbsoluteComplete") < out.index("move-absolute: done (moveAbsoluteComplete)")


def test_shell_completion_of_names_options_enums_files_and_values(tmp_path: Path) -> None:
    from prompt_toolkit.completion import CompleteEvent
    from prompt_toolkit.document import Document

    from landscape.cli import shell_completer

    (tmp_path / "square.csv").write_text("j1\n0\n")
    comp = shell_completer(["move-absolute", "move-arc", "path", "path-move", "get-tool", "set-units"],
                           lambda: ["path-move square", "get-tool gripper", "path-move 'corner run'"])

    def words(text: str) -> set[str]:
        return {c.text for c in comp.get_completions(Document(text), CompleteEvent(completion_requested=True))}
    assert words("move-a") == {"move-absolute", "move-arc"}
    assert {"joint", "joint_frame", "base_cartesian"} <= words("move-absolute p1 ")           # an enum value
    assert words("move-absolute p1 jo") == {"joint", "joint_frame"}
    assert "--speed-pct" in words("move-absolute p1 joint 0 0 0 0 0 0 --sp")                  # an option name
    assert words("set-units millimeters d") == {"degrees", "deg"}                              # 2nd enum
    assert words("path-move ") == {"square", "'corner run'"}                                   # path names typed before
    assert words("get-tool g") == {"gripper"}                                                  # tools typed before
    assert words(f"path load {tmp_path}/sq") == {"uare.csv"}                                   # file names
    assert "load" in words("path ")


def test_one_shot_lock_says_it_ends_with_the_invocation(channel: str, device: FakeDevice, tmp_path: Path) -> None:
    r = run(channel, "lock")
    assert r.exit_code == 0, r.stderr
    assert r.stdout.splitlines()[0] == "lock: CMD_EXEC_OK"
    assert ("  note: this lock ends when this invocation exits (it disconnects, and the device releases it); to "
            "keep it across invocations run `landscape session start` first") in r.stdout
    r = run(channel, "--json", "lock")
    assert "landscape session start" in json.loads(r.stdout)["note"]
    # in a run file the lock lives on for the file's later lines: no note
    script = tmp_path / "lock.ls"
    script.write_text("lock\nrelease\n")
    r = run(channel, "run", str(script))
    assert r.exit_code == 0 and "note:" not in r.stdout


@pytest.mark.parametrize("command", ["move-react", "comply"])
def test_help_of_move_react_and_comply_explains_every_option(command: str) -> None:
    from landscape.cli_core import OPTION_HELP
    from landscape.registry import lookup

    cmd = lookup(command)
    r = CliRunner().invoke(cli, [command, "--help"], terminal_width=200)
    assert r.exit_code == 0
    text = " ".join(r.stdout.split())
    assert "Example" in text and f"landscape {command} force_sensor" in text
    for f in cmd.fields():
        opt = "--" + f.name.replace("_", "-")
        if opt in text:  # every option carries its own help, with a unit or what the firmware does with it
            helptext = OPTION_HELP[(cmd.field, f.name)]
            assert " ".join(helptext.split()) in text, opt
            assert any(w in helptext for w in ("%", " N", "s ", "linear unit", "not used", "integer")), opt


@pytest.mark.parametrize("command", ["move-absolute", "move-relative"])
def test_help_of_a_move_says_how_many_values_in_which_units_and_what_speed_0_means(command: str) -> None:
    r = CliRunner().invoke(cli, [command, "--help"], terminal_width=200)
    assert r.exit_code == 0
    text = " ".join(r.stdout.split())
    for said in ("one value per joint", "6 values x y z roll pitch yaw", "in the angular unit",
                 "R = Rz(yaw) Ry(pitch) Rx(roll)", "0: the current set-speed", "Example", f"landscape {command} "):
        assert said in text, said


def test_numbers_show_without_float_noise() -> None:
    from landscape.cli_core import fmt_value

    assert [fmt_value(v) for v in (1.6661e-10, -1e-12, -0.0, 0.3356, 123.4567, 2e-9)] == \
        ["0", "0", "0", "0.3356", "123.457", "2e-09"]
    assert fmt_value([0.1, -3.2e-11]) == "0.1 0"


def test_set_units_needs_both_units() -> None:
    r = CliRunner().invoke(cli, ["--interface", "virtual", "--channel", "nowhere", "set-units", "millimeters"])
    assert r.exit_code == 2
    assert one_line_error(r).startswith("landscape: error: Missing argument 'ANGULAR'")
    r = CliRunner().invoke(cli, ["set-units", "--help"], terminal_width=200)
    assert "never changes silently" in " ".join(r.stdout.split())


def test_monitor_shows_telemetry_in_the_session_units() -> None:
    """Telemetry is SI; monitor converts it to the session's units and labels every row."""
    import math

    from rich.console import Console

    from landscape.cli import monitor_view
    from landscape.notices import Units

    t = {"JOINTS_12": {"j1": math.pi / 2, "j2": 0.0}, "TOOL_POS": {"tool_x": 0.5, "tool_y": 0.0, "tool_z": -0.25},
         "TOOL_RPY": {"tool_roll": math.pi, "tool_pitch": 0.0, "tool_yaw": 0.0}}
    console = Console(width=200, record=True)
    console.print(monitor_view(t, "m", [], Units("millimeters", "degrees")))
    text = console.export_text()
    assert "millimeters and degrees (the session's, get-units)" in text
    assert "joints (deg)" in text and "+90.0000 +0.0000" in text
    assert "tool xyz (mm)" in text and "+500.0000 +0.0000 -250.0000" in text
    assert "tool rpy (deg)" in text and "+180.0000" in text
    console = Console(width=200, record=True)
    console.print(monitor_view(t, "m", [], None))
    text = console.export_text()
    assert "the session's units are unknown" in text and "joints (rad)" in text and "+1.5708" in text
