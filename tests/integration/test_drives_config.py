"""The drive arm's configuration as a user meets it: what landscaped and `--check` say
about a drive bus over its budget, an EDS that lacks what cyclic synchronous position
needs, a drive that does not answer and a drive with another identity than its EDS
(docs/deploy.md "Drives"). Each is one clear line at start and in --check."""
from __future__ import annotations

import re
import socket
import subprocess
from pathlib import Path

from canopen_local_drives import ROS2_EDS
from conftest import DRIVE_NODES, LANDSCAPED, SIMDRIVE_EDS, drive_config, start_simdrives, stop_drives


def _landscaped(*args: str, timeout: float = 60) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(LANDSCAPED), *args, "--rt-priority", "0", "--no-lock-memory"], capture_output=True,
                          text=True, timeout=timeout)


def _errors(r: subprocess.CompletedProcess[str]) -> list[str]:
    return [ln for ln in r.stderr.splitlines() if ln.startswith("<3>")]


def _fails(r: subprocess.CompletedProcess[str]) -> list[str]:
    return [ln for ln in r.stdout.splitlines() if ln.startswith("FAIL")]


def _without(eds: Path, section: str, out: Path) -> Path:
    """A copy of `eds` without object `section` (its sub-objects too) and its list entry."""
    text = eds.read_text(errors="replace")
    blocks = re.split(r"(?m)^(?=\[)", text)
    kept = [b for b in blocks if not re.match(rf"\[{section}(sub[0-9A-Fa-f]+)?\]", b, re.I)]
    body = "".join(kept)
    body = re.sub(rf"(?m)^\d+=0x{section}\r?\n", "", body)
    out.write_text(body)
    return out


def test_a_drive_bus_over_its_budget_is_refused_naming_the_cycle_that_fits(tmp_path: Path) -> None:
    conf = drive_config(tmp_path / "d.conf", tmp_path / "nothing-here", cycle="1")
    r = _landscaped("--config", str(conf), "--link", f"slcan:pty:{tmp_path / 'ls0'}")
    assert r.returncode == 2, r.stderr
    [line] = _errors(r)
    assert re.search(r"drive bus: [\d,]+ bit-times per 1 ms cycle = \d+ % of 1 Mbit/s, above the 70 % ceiling: "
                     r"set \[drives\] cycle = [234] \([234] ms\) or more", line), line
    r = _landscaped("--config", str(conf), "--link", f"slcan:pty:{tmp_path / 'ls0'}", "--check")
    assert r.returncode == 2, r.stdout
    assert any(ln.startswith("FAIL  drive bus budget: drive bus:") and "above the 70 % ceiling" in ln
               for ln in _fails(r)), r.stdout


def test_an_eds_without_the_target_position_is_refused_naming_joint_file_and_object(tmp_path: Path) -> None:
    bad = _without(SIMDRIVE_EDS, "607A", tmp_path / "no-target.eds")
    conf = drive_config(tmp_path / "d.conf", tmp_path / "nothing-here")
    text = conf.read_text().replace(f"eds = {SIMDRIVE_EDS}", f"eds = {bad}", 3)  # joints 1-3
    conf.write_text(text)
    r = _landscaped("--config", str(conf), "--link", f"slcan:pty:{tmp_path / 'ls0'}")
    assert r.returncode == 2, r.stderr
    [line] = _errors(r)
    assert f"[joint.1] eds {bad}: the drive lacks 0x607A target position, mappable into an RPDO" in line, line
    r = _landscaped("--config", str(conf), "--link", f"slcan:pty:{tmp_path / 'ls0'}", "--check")
    assert r.returncode == 2, r.stdout
    assert any("the drive lacks 0x607A target position" in ln for ln in _fails(r)), r.stdout


def test_an_eds_that_is_no_eds_is_refused_with_its_file_and_line(tmp_path: Path) -> None:
    bad = tmp_path / "notes.txt"
    bad.write_text("this is not an electronic data sheet\n")
    conf = drive_config(tmp_path / "d.conf", tmp_path / "nothing-here")
    conf.write_text(conf.read_text().replace(f"eds = {SIMDRIVE_EDS}", f"eds = {bad}", 1))
    r = _landscaped("--config", str(conf), "--link", f"slcan:pty:{tmp_path / 'ls0'}")
    assert r.returncode == 2, r.stderr
    [line] = _errors(r)
    assert f"[joint.1] eds: {bad}:" in line, line


def test_a_vendor_eds_without_0x6007_is_a_warning_not_a_refusal(tmp_path: Path) -> None:
    conf = drive_config(tmp_path / "d.conf", tmp_path / "nothing-here")
    conf.write_text(conf.read_text().replace(f"eds = {SIMDRIVE_EDS}", f"eds = {ROS2_EDS}", 1))
    r = _landscaped("--config", str(conf), "--link", f"slcan:pty:{tmp_path / 'ls0'}", "--check")
    warns = [ln for ln in r.stdout.splitlines() if ln.startswith("WARN  drives:")]
    assert any("joint 1 (node 0x21): its EDS has no writable 0x6007" in w for w in warns), r.stdout
    # and the bus that is not there is named
    assert any(ln.startswith("FAIL  drive bus: [drives] link slcan:tty:") for ln in _fails(r)), r.stdout


def test_a_drive_that_does_not_answer_is_named_at_start_and_in_check(tmp_path: Path) -> None:
    drives, _ = start_simdrives(tmp_path / "drv", "--nodes", ",".join(f"{n:#x}" for n in DRIVE_NODES[:5]))
    try:
        conf = drive_config(tmp_path / "d.conf", tmp_path / "drv", boot_timeout_ms="500")
        r = _landscaped("--config", str(conf), "--link", f"slcan:pty:{tmp_path / 'ls0'}", "--check")
        assert r.returncode == 1, r.stdout
        [fail] = _fails(r)
        assert fail.startswith("FAIL  drive of joint 6 (node 0x26): does not answer"), r.stdout
        assert "is it powered, on slcan:tty:" in fail
        r = _landscaped("--config", str(conf), "--link", f"slcan:pty:{tmp_path / 'ls0'}")
        assert r.returncode == 1, r.stderr
        [line] = _errors(r)
        assert "drives: joint 6: node 0x26: no boot-up within 500 ms" in line, line
    finally:
        stop_drives(drives)


def test_a_drive_with_another_identity_is_named_at_start_and_in_check(tmp_path: Path) -> None:
    drives, control = start_simdrives(tmp_path / "drv")
    try:
        with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as s:
            s.sendto(b"identity 0x23 0x12345678 0x9", str(control))
        conf = drive_config(tmp_path / "d.conf", tmp_path / "drv")
        r = _landscaped("--config", str(conf), "--link", f"slcan:pty:{tmp_path / 'ls0'}", "--check")
        assert r.returncode == 1, r.stdout
        [fail] = _fails(r)
        assert fail.startswith("FAIL  drive of joint 3 (node 0x23): identity vendor 0x12345678"), r.stdout
        assert "another drive at this node id, or the wrong EDS" in fail
        r = _landscaped("--config", str(conf), "--link", f"slcan:pty:{tmp_path / 'ls0'}")
        assert r.returncode == 1, r.stderr
        [line] = _errors(r)
        assert "drives: joint 3: node 0x23: vendor id 0x1018:01 is 0x12345678, the EDS says" in line, line
    finally:
        stop_drives(drives)
