"""The drives' readouts (docs/protocol.md "Drives"): what `sendCommand drives N` and
`sendCommand drives bus` answer, as typed values, and the table `landscape drives` shows.

Pure: the requests are built here (``joint_request``, ``BUS_REQUEST``) and the answers
parsed; sending them is the caller's (the CLI, a Supervisor).
"""
from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import asdict, dataclass, field
from typing import Any

from .errors import ProtocolError

#: The sendCommand input of the drive bus master's counters.
BUS_REQUEST = "drives bus"
#: The sendCommand input of the homing: every joint that must be homed, or those named.
HOME_REQUEST = "home"


def joint_request(joint: int) -> str:
    """The sendCommand input of one joint's readouts in full (joint 1..)."""
    return f"drives {joint}"


def home_request(joints: tuple[int, ...] = ()) -> str:
    """The sendCommand input that homes `joints` (none: every joint that must be homed)."""
    return " ".join([HOME_REQUEST, *(str(j) for j in joints)])


@dataclass(frozen=True)
class DriveReadout:
    """One joint's drive as it reports itself (every value the drive's, not the command)."""

    joint: int
    node: str                   # "0x21"
    state: str                  # CiA 402 power state, "OPERATION ENABLED"
    statusword: str             # "0x1637"
    mode: int                   # mode of operation displayed (0x6061); 0: unknown
    home: str                   # not_homed, homing, homed, failed
    home_required: bool
    error: str                  # the last EMCY's code, "0x0000" when none
    error_name: str
    position_rad: float
    feedback_age_cycles: int
    velocity_rad_s: float | None = None   # where the drive maps them
    torque_permille: int | None = None
    temperature_c: float | None = None
    brake: str | None = None              # engaged / released
    sto: str | None = None                # active / off

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def _pairs(text: str) -> dict[str, str]:
    out: dict[str, str] = {}
    for line in text.splitlines():
        key, sep, value = line.partition("=")
        if sep:
            out[key.strip()] = value.strip()
    return out


def parse_joint(text: str) -> DriveReadout:
    """The answer of ``joint_request``: ProtocolError when a key every answer carries is
    missing or malformed (a firmware of another version: update the host tool)."""
    kv = _pairs(text)
    try:
        return DriveReadout(
            joint=int(kv["joint"]), node=kv["node"], state=kv["state"], statusword=kv["statusword"],
            mode=int(kv["mode"]), home=kv["home"], home_required=kv["home_required"] == "yes",
            error=kv["error"], error_name=kv["error_name"], position_rad=float(kv["position_rad"]),
            feedback_age_cycles=int(kv["feedback_age_cycles"]),
            velocity_rad_s=float(kv["velocity_rad_s"]) if "velocity_rad_s" in kv else None,
            torque_permille=int(kv["torque_permille"]) if "torque_permille" in kv else None,
            temperature_c=float(kv["temperature_c"]) if "temperature_c" in kv else None,
            brake=kv.get("brake"), sto=kv.get("sto"))
    except (KeyError, ValueError) as exc:
        raise ProtocolError(f"sendCommand drives: an answer this host tool cannot read ({exc}): update the host "
                            f"tool to the firmware's version") from None


def parse_bus(text: str) -> dict[str, int]:
    """The answer of ``BUS_REQUEST``: counter name -> value."""
    try:
        return {k: int(v) for k, v in _pairs(text).items()}
    except ValueError as exc:
        raise ProtocolError(f"sendCommand {BUS_REQUEST}: a counter this host tool cannot read ({exc})") from None


@dataclass
class DrivesView:
    """Every joint's readouts and the bus counters, for a table or JSON."""

    drives: list[DriveReadout] = field(default_factory=list)
    bus: dict[str, int] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        return {"drives": [d.as_dict() for d in self.drives], "bus": dict(self.bus)}

    def lines(self) -> Iterator[str]:
        """A fixed-width table, one row per joint, then the bus counters on one line."""
        cols = ("joint", "node", "state", "mode", "home", "brake", "sto", "error", "position", "velocity",
                "torque", "temp", "age")
        rows = [cols] + [_row(d) for d in self.drives]
        widths = [max(len(r[i]) for r in rows) for i in range(len(cols))]
        for r in rows:
            yield "  ".join(v.ljust(w) for v, w in zip(r, widths, strict=True)).rstrip()
        if self.bus:
            yield "bus: " + " ".join(f"{k}={v}" for k, v in self.bus.items())


def _opt(v: float | int | str | None, fmt: str) -> str:
    return "-" if v is None else format(v, fmt)


def _row(d: DriveReadout) -> tuple[str, ...]:
    home = d.home + ("*" if d.home_required and d.home != "homed" else "")
    error = d.error if d.error == "0x0000" else f"{d.error} {d.error_name}"
    return (str(d.joint), d.node, d.state, str(d.mode), home, d.brake or "-", d.sto or "-", error,
            f"{d.position_rad:+.4f} rad", _opt(d.velocity_rad_s, "+.3f"),
            "-" if d.torque_permille is None else f"{d.torque_permille / 10:+.1f} %",
            "-" if d.temperature_c is None else f"{d.temperature_c:.1f} C", f"{d.feedback_age_cycles}")


def view_from(answers: Mapping[str, str], joints: int) -> DrivesView:
    """The view from the answers to ``joint_request(1..joints)`` and ``BUS_REQUEST`` (by request)."""
    return DrivesView([parse_joint(answers[joint_request(j)]) for j in range(1, joints + 1)],
                      parse_bus(answers.get(BUS_REQUEST, "")))
