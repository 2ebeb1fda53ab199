"""Deployment (docs/deploy.md): the install layout, the Debian package installed
for real with dpkg (the CI machine is a throwaway root), the systemd unit,
`--check` on this machine and configuration errors as the user sees them.

The configuration checks run on two executables: ls_config_driver (makes the
same calls as landscaped's main) and landscaped itself (its --config and
--check): the same cases run on each."""
from __future__ import annotations

import grp
import os
import pwd
import re
import shutil
import socket
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from conftest import BUILD, LANDSCAPED, ROOT

DEPLOY = ROOT / "firmware" / "app" / "deploy"
DRIVER = BUILD / "bin" / "ls_config_driver"
CONF = DEPLOY / "landscaped.conf"
GATEWAY_CONF = DEPLOY / "gateway.toml"
GATEWAY_UNIT = "landscape-gateway.service"
#: Where the gateway's unit runs the host tool from (docs/gateway.md "Installation").
GATEWAY_EXE = Path("/opt/landscape/bin/landscape")
PACKAGE = "landscape-controller"

PACKAGED_FILES = {
    "/etc/landscape/landscaped.conf",
    "/etc/landscape/gateway.toml",
    "/usr/bin/landscaped",
    "/usr/bin/ls-simdrives",
    "/usr/share/landscape/ls-simdrive.eds",
    "/usr/lib/systemd/system/landscaped.service",
    "/usr/lib/systemd/system/landscape-gateway.service",
    "/usr/lib/sysusers.d/landscape.conf",
    "/usr/lib/udev/rules.d/60-landscape-gpio.rules",
    "/usr/lib/udev/rules.d/60-landscape-input.rules",
} | {f"/usr/share/doc/landscape/{p.name}" for p in (ROOT / "docs").glob("*.md")} \
  | {f"/usr/share/landscape/robots/{p.name}" for p in (ROOT / "firmware" / "model" / "robots").glob("*.ini")}


def run(*args: str | Path, timeout: float = 120, check: bool = False) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(a) for a in args], capture_output=True, text=True, timeout=timeout, check=check)


def kernel_has_afcan() -> bool:
    try:
        s = socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
    except OSError:
        return False
    s.close()
    return True


def require_built(path: Path) -> None:
    if not path.exists():
        raise AssertionError(f"{path} is missing: build first (cmake --build {BUILD})")


@pytest.fixture(scope="module")
def deb(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The .deb built by cpack from the build directory into a temp dir."""
    require_built(LANDSCAPED)
    out = tmp_path_factory.mktemp("deb")
    r = run("cpack", "--config", BUILD / "CPackConfig.cmake", "-B", out, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    debs = list(out.glob(f"{PACKAGE}_*.deb"))
    assert len(debs) == 1, f"cpack made {debs}: {r.stdout}"
    return debs[0]


# ---- the package ------------------------------------------------------------

def test_deb_holds_exactly_the_deployed_files(deb: Path) -> None:
    r = run("dpkg-deb", "-c", deb, check=True)
    files = {line.split()[-1].removeprefix(".") for line in r.stdout.splitlines() if not line.startswith("d")}
    assert files == PACKAGED_FILES
    modes = {line.split()[-1].removeprefix("."): line.split()[0] for line in r.stdout.splitlines()}
    assert modes["/usr/bin/landscaped"] == "-rwxr-xr-x"
    assert modes["/etc/landscape/landscaped.conf"] == "-rw-r--r--"
    assert modes["/etc/landscape/gateway.toml"] == "-rw-r-----"  # password hashes


def test_deb_control_fields(deb: Path) -> None:
    def field(name: str) -> str:
        return run("dpkg-deb", "-f", deb, name, check=True).stdout.strip()

    assert field("Package") == PACKAGE
    assert field("Version") == re.search(r"project\(landscape VERSION ([0-9.]+)",
                                         (ROOT / "CMakeLists.txt").read_text()).group(1)
    depends = [d.strip().split()[0] for d in field("Depends").split(",")]
    for lib in ("libode8", "libgpiod2", "libinih1", "libevdev2", "libc6"):
        assert lib in depends, field("Depends")
    assert re.fullmatch(r".+ <[^@ ]+@[^> ]+>", field("Maintainer")), field("Maintainer")
    conffiles = run("dpkg-deb", "-I", deb, "conffiles", check=True).stdout.split()
    assert conffiles == ["/etc/landscape/landscaped.conf", "/etc/landscape/gateway.toml"]
    for script in ("postinst", "prerm", "postrm"):
        text = run("dpkg-deb", "-I", deb, script, check=True).stdout
        assert text.startswith("#!/bin/sh\n") and "set -e" in text
        assert run("sh", "-n", DEPLOY / script).returncode == 0


def test_cmake_install_layout(tmp_path: Path) -> None:
    require_built(LANDSCAPED)
    r = run("cmake", "--install", BUILD, "--prefix", tmp_path, check=True)
    files = {str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*") if p.is_file()}
    assert files == {f.removeprefix("/usr/").removeprefix("/") for f in PACKAGED_FILES}, r.stdout
    assert (tmp_path / "etc/landscape/landscaped.conf").read_text() == CONF.read_text()
    assert (tmp_path / "etc/landscape/gateway.toml").read_text() == GATEWAY_CONF.read_text()
    assert os.access(tmp_path / "bin/landscaped", os.X_OK)


# ---- the unit ---------------------------------------------------------------

def unit_directives(unit: str = "landscaped.service") -> dict[str, list[str]]:
    d: dict[str, list[str]] = {}
    for line in (DEPLOY / unit).read_text().splitlines():
        m = re.match(r"^(\w+)=(.*)$", line)
        if m:
            d.setdefault(m.group(1), []).append(m.group(2))
    return d


def test_unit_directives() -> None:
    d = unit_directives()
    want = {
        "Type": ["simple"],
        "ExecStart": ["/usr/bin/landscaped --config /etc/landscape/landscaped.conf"],
        "User": ["landscape"],
        "Restart": ["on-failure"],
        "RestartSec": ["1"],
        "LimitRTPRIO": ["99"],
        "LimitMEMLOCK": ["infinity"],
        "AmbientCapabilities": ["CAP_SYS_NICE CAP_IPC_LOCK"],
        "CapabilityBoundingSet": ["CAP_SYS_NICE CAP_IPC_LOCK"],
        "NoNewPrivileges": ["yes"],
        "ProtectSystem": ["strict"],
        "ProtectHome": ["yes"],
        "PrivateTmp": ["yes"],
        "StandardError": ["journal"],
        "SupplementaryGroups": ["gpio input dialout"],
        "WantedBy": ["multi-user.target"],
    }
    for key, value in want.items():
        assert d.get(key) == value, key
    assert "char-gpiochip rw" in d["DeviceAllow"]
    assert "char-input r" in d["DeviceAllow"]  # the manual devices, read only
    assert "char-ttyACM rw" in d["DeviceAllow"]  # a serial SLCAN adapter on the drive bus
    # RestrictRealtime=yes would forbid the SCHED_FIFO the control loop asks for
    assert d.get("RestrictRealtime", ["no"]) == ["no"]
    # the gpio group and the landscape user the unit names come from sysusers
    sysusers = (DEPLOY / "landscape.sysusers").read_text()
    assert re.search(r"^u landscape ", sysusers, re.M) and re.search(r"^g gpio ", sysusers, re.M)
    assert re.search(r"^m landscape gpio$", sysusers, re.M)
    assert re.search(r"^g input ", sysusers, re.M) and re.search(r"^m landscape input$", sysusers, re.M)
    assert 'GROUP="gpio"' in (DEPLOY / "60-landscape-gpio.rules").read_text()
    assert 'GROUP="input"' in (DEPLOY / "60-landscape-input.rules").read_text()


def test_gateway_unit_directives() -> None:
    d = unit_directives(GATEWAY_UNIT)
    want = {
        "Type": ["simple"],
        "ExecStart": [f"{GATEWAY_EXE} gateway --config /etc/landscape/gateway.toml"],
        "User": ["landscape"],
        "Restart": ["on-failure"],
        "NoNewPrivileges": ["yes"],
        "ProtectSystem": ["strict"],
        "ProtectHome": ["yes"],
        "PrivateTmp": ["yes"],
        "KillSignal": ["SIGTERM"],
        "WantedBy": ["multi-user.target"],
    }
    for key, value in want.items():
        assert d.get(key) == value, key
    # the OPC UA clients reach it over TCP; no capability at all
    assert {"AF_INET", "AF_INET6"} <= set(d["RestrictAddressFamilies"][0].split())
    assert d["CapabilityBoundingSet"] == [""]


def test_shipped_gateway_config_is_valid_and_safe() -> None:
    from landscape.gateway_config import load_config
    cfg = load_config(GATEWAY_CONF)
    assert cfg.host == "127.0.0.1" and cfg.port == 4840  # this machine only, OPC UA's port
    assert cfg.allow_anonymous and not cfg.users and not cfg.certificate_users  # read-only until configured
    assert (cfg.interface, cfg.channel) == ("socketcan", "can0")  # landscaped.conf's link


# ---- installed for real -------------------------------------------------------

@pytest.fixture(scope="module")
def installed(deb: Path) -> Iterator[Path]:
    """dpkg -i the package, yield, then purge it and drop the user and group
    if they did not exist before (leave the machine as found)."""
    if os.geteuid() != 0:
        pytest.skip("installing the .deb needs root: the CI machine runs this tier as root")
    if run("dpkg-query", "-W", "-f", "${Status}", PACKAGE).stdout.startswith("install ok"):
        pytest.skip(f"{PACKAGE} is already installed on this machine: not touching a real installation")
    had_user = _exists(pwd.getpwnam, "landscape")
    had_group = _exists(grp.getgrnam, "gpio")
    r = run("dpkg", "-i", deb, timeout=300)
    try:
        assert r.returncode == 0, r.stdout + r.stderr
        yield deb
    finally:
        r_purge = run("dpkg", "-P", PACKAGE, timeout=300)
        if not had_user and _exists(pwd.getpwnam, "landscape"):
            run("userdel", "landscape")
        if not had_group and _exists(grp.getgrnam, "gpio"):
            run("groupdel", "gpio")
        assert r_purge.returncode == 0, r_purge.stdout + r_purge.stderr
        assert not Path("/usr/bin/landscaped").exists()
        assert not Path("/etc/landscape").exists(), "purge leaves /etc/landscape behind"


def _exists(lookup, name: str) -> bool:  # type: ignore[no-untyped-def]
    try:
        lookup(name)
        return True
    except KeyError:
        return False


def test_installed_package(installed: Path) -> None:
    listed = set(run("dpkg", "-L", PACKAGE, check=True).stdout.split())
    assert PACKAGED_FILES <= listed
    user = pwd.getpwnam("landscape")
    assert user.pw_shell == "/usr/sbin/nologin"
    assert "landscape" in grp.getgrnam("gpio").gr_mem
    assert Path("/usr/bin/landscaped").read_bytes() != b""


def test_installed_unit_verifies(installed: Path) -> None:
    if shutil.which("systemd-analyze") is None:
        raise AssertionError("systemd-analyze is missing: install the Debian package 'systemd' (.ci/setup)")
    r = run("systemd-analyze", "verify", "/usr/lib/systemd/system/landscaped.service")
    assert r.returncode == 0, r.stdout + r.stderr
    assert "landscaped.service" not in r.stdout + r.stderr, r.stdout + r.stderr


def test_installed_gateway_unit_and_config(installed: Path) -> None:
    conf = Path("/etc/landscape/gateway.toml")
    st = conf.stat()
    assert oct(st.st_mode & 0o777) == "0o640" and grp.getgrgid(st.st_gid).gr_name == "landscape"
    # systemd-analyze verify checks that ExecStart is executable: the host tool of this checkout,
    # installed where the unit expects it (docs/gateway.md "Installation"), for the check only
    cli = Path(sys.executable).parent / "landscape"
    if GATEWAY_EXE.parent.parent.exists():
        pytest.skip(f"{GATEWAY_EXE.parent.parent} exists on this machine: not touching a real installation")
    GATEWAY_EXE.parent.mkdir(parents=True)
    try:
        GATEWAY_EXE.symlink_to(cli)
        r = run("systemd-analyze", "verify", f"/usr/lib/systemd/system/{GATEWAY_UNIT}")
        assert r.returncode == 0, r.stdout + r.stderr
        assert GATEWAY_UNIT not in r.stdout + r.stderr, r.stdout + r.stderr
    finally:
        shutil.rmtree(GATEWAY_EXE.parent.parent)


def test_installed_config_checks_this_machine(installed: Path) -> None:
    require_built(DRIVER)
    r = run(DRIVER, "--config", "/etc/landscape/landscaped.conf", "--check")
    assert r.stdout.startswith("PASS  configuration: /etc/landscape/landscaped.conf: node 0x10, 1 link(s)"), r.stdout
    if not kernel_has_afcan():
        assert r.returncode == 1
        assert "\nFAIL  AF_CAN: " in r.stdout


def test_upgrade_keeps_the_edited_config(installed: Path) -> None:
    conf = Path("/etc/landscape/landscaped.conf")
    edited = conf.read_text().replace("name = landscape\n", "name = cell-7\n")
    assert edited != conf.read_text()
    conf.write_text(edited)
    r = run("dpkg", "-i", installed, timeout=300)  # reinstall = the upgrade path of the maintainer scripts
    assert r.returncode == 0, r.stdout + r.stderr
    assert conf.read_text() == edited


# ---- --check and configuration errors, end to end -----------------------------

def executable(which: str) -> Path:
    if which == "driver":
        require_built(DRIVER)
        return DRIVER
    require_built(LANDSCAPED)
    return LANDSCAPED


@pytest.mark.parametrize("which", ["driver", "landscaped"])
def test_check_names_afcan_and_the_gpiochip(which: str, tmp_path: Path) -> None:
    exe = executable(which)
    conf = tmp_path / "l.conf"
    conf.write_text("[hal]\nlink = socketcan:can0\ndio = gpiod:gpiochip0\n[dio]\ninputs = 0,1\n")
    r = run(exe, "--config", conf, "--check", "--rt-priority", "0", "--no-lock-memory", timeout=30)
    lines = r.stdout.splitlines()
    assert lines[0] == (f"PASS  configuration: {conf}: node 0x10, 1 link(s), arm sim, dio gpiod:gpiochip0, "
                        "clock realtime, 1000 Hz")
    by_what = {re.sub(r":.*", "", ln[6:]): ln[:4] for ln in lines[:-1]}
    have_afcan = kernel_has_afcan()
    have_chip = Path("/dev/gpiochip0").exists()
    assert by_what["AF_CAN"] == ("PASS" if have_afcan else "FAIL")
    assert by_what["gpio chip gpiochip0"] == ("PASS" if have_chip else "FAIL")
    if not have_afcan:
        assert any(ln.startswith("FAIL  AF_CAN: ") and "modprobe can can-raw" in ln for ln in lines)
        assert any(ln.startswith("FAIL  link socketcan:can0: ") for ln in lines)
    if not have_chip:
        assert "FAIL  gpio chip gpiochip0: no GPIO chip 'gpiochip0' (ls /dev/gpiochip*; " in r.stdout
    if not (have_afcan and have_chip):
        assert r.returncode == 1
        assert lines[-1].startswith("landscaped cannot run with this configuration: ")


@pytest.mark.parametrize("which", ["driver", "landscaped"])
def test_check_of_the_shipped_config(which: str) -> None:
    exe = executable(which)
    r = run(exe, "--config", CONF, "--check", timeout=30)
    assert "PASS  configuration: " in r.stdout
    if not kernel_has_afcan():
        assert r.returncode == 1 and "FAIL  AF_CAN: " in r.stdout


@pytest.mark.parametrize("which", ["driver", "landscaped"])
@pytest.mark.parametrize("text,tail", [
    ("[device]\nname = x\n[control]\nrate_hz = 5\n",
     "4: [control] rate_hz: got '5', expected 100..10000 (control cycles per second)"),
    ("[device]\nnode = abc\n",
     "2: [device] node: got 'abc', expected 1..0xFE (node address; 0xFF is the broadcast address)"),
    ("[control]\nrate = 100\n",
     "2: [control] rate: unknown key; expected one of rate_hz, telemetry_hz, rt_priority, rt_cpu, lock_memory"),
    ("[hal]\narm = sim\narm = none\n", "3: [hal] arm: given twice (first on line 2); keep one"),
    ("[hal]\nsetpoint_trace = /tmp/\n", "2: [hal] setpoint_trace: got '/tmp/', expected the path of a file to "
     "write, of at most 255 characters, or nothing for none"),
])
def test_config_error_is_one_line_with_file_key_and_reason(which: str, text: str, tail: str, tmp_path: Path) -> None:
    exe = executable(which)
    conf = tmp_path / "bad.conf"
    conf.write_text(text)
    r = run(exe, "--config", conf, "--link", "slcan:pty:/tmp/never", timeout=30)
    assert r.returncode == 2
    assert r.stderr == f"<3>landscaped: error: {conf}:{tail}\n"
    assert not Path("/tmp/never").exists()
    # with --check the same message is the FAIL line, and the exit code the same
    r = run(exe, "--config", conf, "--check", timeout=30)
    assert r.returncode == 2
    assert r.stdout.splitlines()[0] == f"FAIL  configuration: {conf}:{tail}"


@pytest.mark.parametrize("which", ["driver", "landscaped"])
def test_missing_config_file(which: str, tmp_path: Path) -> None:
    exe = executable(which)
    r = run(exe, "--config", tmp_path / "nope.conf", timeout=30)
    assert r.returncode == 2
    assert r.stderr == (f"<3>landscaped: error: {tmp_path}/nope.conf: cannot read the configuration file: "
                        "No such file or directory (give an existing file with --config FILE)\n")


def test_options_override_the_file(tmp_path: Path) -> None:
    require_built(DRIVER)
    conf = tmp_path / "l.conf"
    conf.write_text("[device]\nname = from-file\n[hal]\nlink = socketcan:can0\n[control]\nrate_hz = 500\n"
                    "rt_priority = 50\n")
    r = run(DRIVER, "--config", conf, "--rate", "2000", "--link", "slcan:pty:/run/landscape/ls0", "--hal", "sim",
            check=True)
    got = dict(ln.split(" = ", 1) if " = " in ln else (ln.rstrip(" ="), "") for ln in r.stdout.splitlines())
    assert got["name"] == "from-file"
    assert got["rate_hz"] == "2000"
    assert got["rt_priority"] == "50"
    assert got["link"] == "slcan:pty:/run/landscape/ls0"
    assert got["dio"] == "sim"


# ---- docs ---------------------------------------------------------------------

def test_deploy_doc_lists_every_key() -> None:
    """docs/deploy.md's key table, the shipped file and ls_config.h agree."""
    doc = (ROOT / "docs" / "deploy.md").read_text()
    table = set(re.findall(r"^\| `\[(\w+(?:\.N)?)\] (\w+)` \|", doc, re.M))
    shipped = set()
    section = ""
    for line in CONF.read_text().splitlines():
        if m := re.match(r"^\[(\w+)(\.\d)?\]$", line):
            section = m.group(1) + (".N" if m.group(2) else "")
        elif m := re.match(r"^(\w+) =", line):
            shipped.add((section, m.group(1)))
    header = set(re.findall(r"/\* (\w+) = ", (ROOT / "firmware" / "app" / "ls_config.h").read_text()))
    assert table == shipped
    assert {k for _, k in table} == header
    for needle in ("ip link set can0 type can bitrate 500000", "vcan", "journalctl -u landscaped -p warning",
                   "--check", "systemctl enable --now landscaped", "60-landscape-gpio.rules", "dpkg -i"):
        assert needle in doc, needle


@pytest.mark.parametrize("which", ["driver", "landscaped"])
def test_a_configuration_refused_as_a_whole_exits_2_with_check_too(which: str, tmp_path: Path) -> None:
    """Keys that are each valid but not together (ls_config_validate): --check refused them with
    exit 1, as if the machine were at fault, where starting with them exits 2 (docs/deploy.md
    section 5). Found by tests/probe/probe.py."""
    exe = executable(which)
    conf = tmp_path / "estop.conf"
    conf.write_text("[hal]\nlink = slcan:pty:/tmp/never\ndio = gpiod:gpiochip0\n[dio]\ninputs =\nestop_input = 0\n")
    r = run(exe, "--config", conf, "--check", timeout=30)
    assert r.returncode == 2, r.stdout
    assert r.stdout.splitlines()[0] == (f"FAIL  configuration: {conf}: [dio] estop_input = 0 but [dio] inputs is "
                                        "empty: list the e-stop's line under inputs, or set estop_input = -1")
    r = run(exe, "--config", conf, timeout=30)
    assert r.returncode == 2
    assert not Path("/tmp/never").exists()


@pytest.mark.parametrize("which", ["driver", "landscaped"])
@pytest.mark.parametrize("given", ["file", "option"])
def test_setpoint_trace_is_refused_without_the_simulated_arm(which: str, given: str, tmp_path: Path) -> None:
    """[hal] setpoint_trace (--setpoint-trace, a test key: docs/deploy.md "Test-only keys") is
    recorded by the simulated arm: with arm = none the configuration is refused as a whole,
    naming the key, the arm and what to do; nothing is created."""
    exe = executable(which)
    pty = tmp_path / "ls0"
    trace = tmp_path / "setpoints.csv"
    conf = tmp_path / "trace.conf"
    conf.write_text(f"[hal]\nlink = slcan:pty:{pty}\narm = none\ndio = none\n"
                    + (f"setpoint_trace = {trace}\n" if given == "file" else ""))
    option = ["--setpoint-trace", str(trace)] if given == "option" else []
    want = (f"[hal] setpoint_trace = {trace} needs arm = sim: the set-point trace is recorded by the simulated "
            "arm, and arm = none (remove setpoint_trace / --setpoint-trace, or set arm = sim)")
    r = run(exe, "--config", conf, *option, timeout=30)
    assert r.returncode == 2, r.stderr
    assert r.stderr == f"<3>landscaped: error: {want}\n"
    r = run(exe, "--config", conf, *option, "--check", timeout=30)
    assert r.returncode == 2, r.stdout
    assert r.stdout.splitlines()[0] == f"FAIL  configuration: {conf}: {want}"
    assert not pty.exists() and not trace.exists() and not Path(f"{trace}.tmp").exists()
