"""Host exits on hostile input and when the device dies (docs/host-tool.md "Errors and exit codes").

Every failure is one line on stderr with the documented exit code (docs/host-tool.md,
"Errors and exit codes"), never a traceback; a path file is read with a bound taken from
the device's limit (describe: max_points_per_path), so a huge file is refused at once.
"""
from __future__ import annotations

import json
import threading
import time
import tracemalloc
from pathlib import Path

import can
import pytest
from click.testing import CliRunner, Result

from fake_device import FakeDevice
from landscape import LinkLostError, Supervisor
from landscape.cli import cli
from landscape.cli_core import EXIT_BUS, EXIT_USAGE, classify
from landscape.paths import MAX_POINT_TEXT_BYTES, PathFileError, load_path_file, max_file_bytes


def run(channel: str, *args: str) -> Result:
    return CliRunner().invoke(cli, ["--interface", "virtual", "--channel", channel, *args])


#: What `events` says on stderr at its start without a background session (not an error).
EVENTS_NOTE = "events: no background session: "


def single_error(r: Result) -> str:
    assert "Traceback" not in r.stderr + r.stdout
    lines = [line for line in r.stderr.splitlines() if not line.startswith(EVENTS_NOTE)]
    assert len(lines) == 1, r.stderr
    return lines[0]


def load_error(path: Path, max_points: int | None = 256) -> str:
    with pytest.raises(PathFileError) as e:
        load_path_file(path, max_points=max_points)
    text = str(e.value)
    assert "\n" not in text and len(text) < 400, text
    return text


# ---------------------------------------------------------------- path files


def test_a_million_line_csv_is_refused_at_once_by_its_size(tmp_path: Path) -> None:
    f = tmp_path / "huge.csv"
    with f.open("w") as out:
        out.write("j1,j2,j3,j4,j5,j6\n")
        out.writelines(f"{i * 1e-6},0,0,0,0,0\n" for i in range(1_000_000))
    tracemalloc.start()
    t0 = time.monotonic()
    text = load_error(f)
    took = time.monotonic() - t0
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert text == (f"{f}: more than {max_file_bytes(256)} bytes: a path of at most 256 points (the device's "
                    f"limit, describe: max_points_per_path) takes at most {MAX_POINT_TEXT_BYTES} bytes per "
                    f"point; split the file")
    assert took < 1.0 and peak < 4 * max_file_bytes(256), (took, peak)


def test_one_point_more_than_the_device_holds(tmp_path: Path) -> None:
    f = tmp_path / "p.csv"
    f.write_text("j1,j2,j3,j4,j5,j6\n" + "0,0,0,0,0,0\n" * 257)
    assert load_error(f).startswith(f"{f}: line 258: more than 256 points: the device holds at most 256 per path")
    assert len(load_path_file(f, max_points=257).points) == 257
    j = tmp_path / "p.json"
    j.write_text(json.dumps([{"j1": 0.0}] * 11))
    assert load_error(j, 10).startswith(f"{j}: points[10]: more than 10 points")


@pytest.mark.parametrize("suffix,text", [
    (".json", "[" * 100_000 + "]" * 100_000),
    (".json", '{"points": ' + "[" * 5000 + "]" * 5000 + "}"),
    (".yaml", "- " * 5000 + "x\n"),
    (".yaml", "[" * 100_000),
])
def test_deep_nesting_is_one_error(tmp_path: Path, suffix: str, text: str) -> None:
    f = tmp_path / f"deep{suffix}"
    f.write_text(text)
    message = load_error(f, None)
    assert message.startswith(f"{f}: "), message


@pytest.mark.parametrize("suffix,fmt", [
    (".json", '[{{"j1": 0.1, "tag_index": {n}}}]'),
    (".json", '[{{"j1": {n}}}]'),
    (".yaml", "- {{j1: 0.1, tag_index: {n}}}\n"),
    (".csv", "j1,tag_index\n0.1,{n}\n"),
    (".csv", "j1\n{n}\n"),
])
def test_a_5000_digit_integer_is_named_not_printed(tmp_path: Path, suffix: str, fmt: str) -> None:
    f = tmp_path / f"big{suffix}"
    f.write_text(fmt.format(n="7" * 5000))
    message = load_error(f)
    assert message.startswith(f"{f}: ") and "7" * 100 not in message, message
    # its length says what was wrong (YAML reads integers itself: past Python's digit limit)
    assert "(5000 characters)" in message or "an integer of more than 4300 digits" in message, message


def test_a_file_that_is_not_utf8(tmp_path: Path) -> None:
    f = tmp_path / "latin1.csv"
    f.write_bytes(b"j1,tag_name\n0.1,caf\xe9\n")
    assert load_error(f) == f"{f}: line 2: not UTF-8 text (byte 0xe9 at offset 19): save the file as UTF-8"


def test_cli_path_load_uses_the_devices_limit(channel: str, device: FakeDevice, tmp_path: Path) -> None:
    device.max_points_per_path = 50
    f = tmp_path / "sq.csv"
    f.write_text("j1,j2,j3,j4,j5,j6\n" + "0,0,0,0,0,0\n" * 51)
    r = run(channel, "path", "load", str(f))
    assert r.exit_code == EXIT_USAGE
    assert single_error(r).startswith(f"landscape: error: {f}: line 52: more than 50 points: the device holds "
                                      f"at most 50 per path")
    assert not [q for q in device.requests if q.WhichOneof("cmd") == "path_load"]


def test_cli_path_load_of_nested_json_and_a_huge_integer(channel: str, device: FakeDevice, tmp_path: Path) -> None:
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 100_000 + "]" * 100_000)
    r = run(channel, "path", "load", str(deep))
    assert r.exit_code == EXIT_USAGE
    assert single_error(r) == (f"landscape: error: {deep}: nested too deeply: a path file is a list of points "
                               f"(or a mapping with 'points')")
    big = tmp_path / "big.json"
    big.write_text('[{"j1": 0.1, "tag_index": ' + "9" * 5000 + "}]")
    r = run(channel, "path", "load", str(big))
    assert r.exit_code == EXIT_USAGE
    assert single_error(r).startswith(f"landscape: error: {big}: points[0]: tag_index: '9999")
    assert not [q for q in device.requests if q.WhichOneof("cmd") == "path_load"]


def test_run_on_a_script_that_is_not_utf8(channel: str, tmp_path: Path) -> None:
    script = tmp_path / "s.ls"
    script.write_bytes(b"lock\n# caf\xe9\n")
    r = run(channel, "run", str(script))
    assert r.exit_code == EXIT_USAGE
    assert single_error(r) == (f"landscape: error: {script}: line 2: not UTF-8 text (byte 0xe9 at offset 10): "
                               f"save the script as UTF-8")


# ---------------------------------------------------------------- the device dies


def stop_later(device: FakeDevice, after_s: float) -> threading.Thread:
    t = threading.Thread(target=lambda: (time.sleep(after_s), device.stop()), daemon=True)
    t.start()
    return t


def test_a_device_that_dies_during_a_move_is_exit_4_and_one_line(channel: str, device: FakeDevice,
                                                                 tmp_path: Path) -> None:
    device.move_time_s = 60.0
    script = tmp_path / "s.ls"
    script.write_text("lock\nactivate\nmove-absolute p joint 0 0 0 0 0 0 --wait-timeout 60\n")
    t = stop_later(device, 1.0)
    t0 = time.monotonic()
    r = run(channel, "run", str(script))
    took = time.monotonic() - t0
    t.join()
    assert r.exit_code == EXIT_BUS, (r.stdout, r.stderr)
    line = single_error(r)
    assert line.startswith(f"landscape: landscaped at 0x10 on virtual:{channel} stopped answering: no heartbeat "
                           f"from it for "), line
    assert line.endswith("is it still running? Start it again, then rerun the command"), line
    # the device's session time-out is 1 s: silent for twice that, it counts as gone
    assert 2.0 < took < 8.0, took


@pytest.mark.parametrize("command", [["record", "{tmp}/r.csv", "--duration", "30"], ["monitor", "--duration", "30"],
                                     ["events", "--duration", "30"]])
def test_a_device_that_dies_during_record_monitor_events(channel: str, device: FakeDevice, tmp_path: Path,
                                                      command: list[str]) -> None:
    t = stop_later(device, 1.0)
    t0 = time.monotonic()
    r = run(channel, *[c.format(tmp=tmp_path) for c in command])
    t.join()
    assert r.exit_code == EXIT_BUS, (r.stdout, r.stderr)
    assert "stopped answering: no heartbeat from it" in single_error(r)
    assert time.monotonic() - t0 < 8.0


def test_a_link_that_closes_fails_the_waiting_request_at_once(channel: str, device: FakeDevice) -> None:
    bus = can.ThreadSafeBus(interface="virtual", channel=channel)
    with Supervisor(bus, owns_bus=True) as sup:
        device.silent = True  # no answer comes any more: only the closed link can end the wait
        sup.timeout_s = 30.0
        inner = getattr(bus, "__wrapped__", bus)

        def closed(timeout: float | None) -> tuple[None, bool]:
            raise can.CanOperationError("Could not read from serial device") from OSError(5, "Input/output error")
        inner._recv_internal = closed
        t0 = time.monotonic()
        with pytest.raises(LinkLostError) as e:
            sup.get_units()
        assert time.monotonic() - t0 < 2.0
        assert str(e.value) == (f"landscaped at 0x10 on {sup.channel_name} stopped answering: the link closed "
                                f"([Errno 5] Input/output error): is it still running? Start it again, then rerun "
                                f"the command")


def test_a_can_error_below_the_library_is_exit_4() -> None:
    assert classify(can.CanOperationError("Could not write to serial device"))[0] == EXIT_BUS
