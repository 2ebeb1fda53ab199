"""Exception hierarchy of the landscape package.

Every exception derives from LandscapeError and its message says what to do
next. Negative return codes of the device map to one CommandError subclass per
code (``error_for_code``), so callers can catch exactly what they handle.
"""
from __future__ import annotations

from typing import Any

from ._generated import landscape_pb2 as pb


class LandscapeError(Exception):
    """Base of every error raised by this package."""


class BusError(LandscapeError):
    """The CAN bus or channel could not be opened or written."""


class LinkLostError(BusError):
    """The device went away in the middle of a session: the link closed (landscaped exited,
    the adapter was unplugged) or its heartbeat stopped. Nothing more can be done in this
    session; the message says what happened."""


class ControllerTimeoutError(LandscapeError):
    """No controller answered in time (after the retransmissions)."""


class VersionMismatchError(LandscapeError):
    """Host tool and firmware speak different protocol versions or schemas."""


class ProtocolError(LandscapeError):
    """A message from the device could not be decoded or makes no sense."""


class AlarmError(LandscapeError):
    """A non-blocking command ended with an alarm instead of its completion event."""

    def __init__(self, notice: Any, command: str = "") -> None:
        self.notice = notice
        self.command = command
        data = " ".join(notice.data)
        what = f"{command} ended with" if command else "device raised"
        reason = ""
        for item in notice.data:
            key, _, value = str(item).partition("=")
            if key == "reason":
                reason = value
        super().__init__(
            f"{what} alarm {notice.event_id}" + (f" ({data})" if data else "") + ": " + alarm_advice(reason))


#: What to do after a motion's final alarm, by its `reason=` (docs/protocol.md, "Motion lifecycle"): one
#: entry per ending of the schema's enum MotionEnd but "complete" (tests/host/test_errors.py checks).
ADVICE: dict[str, str] = {
    "fault": "the drives are off: read get-motion-control-state for the fault, fix it, then activate again",
    "emergency": "an emergency stop frame stopped the arm and the drives are off: clear the emergency, "
                 "then activate again",
    "deactivate": "the device was deactivated: activate to move again",
    "shutdown": "the controller shut down: restart landscaped, then connect, lock and activate",
    "ownerLost": "the owner's session was lost and the device took its disconnect action (the ownerLost "
                 "alarm's action=): connect again (the lost owner gets a kept lock back), then lock and "
                 "activate as needed",
    "disconnect": "the owner disconnected and the device took its disconnect action (the ownerLost alarm's "
                  "action=): connect again, then lock and activate as needed",
    "auxFailed": "the path stopped at that point; the device is still active (RESTING): fix the auxiliary "
                 "command or its I/O, then start the next motion",
    "abortMotion": "the motion was dropped; the device is RESTING and takes the next motion",
    "rsvpDeclined": "the path was dropped at the RSVP; the device is RESTING and takes the next motion",
}


def alarm_advice(reason: str) -> str:
    """The advice for a motion alarm with data `reason=<reason>`."""
    return ADVICE.get(reason, "read get-motion-control-state for the device's state and fault")


class CommandError(LandscapeError):
    """The device answered a negative return code."""

    code: int = pb.CMD_ERR
    hint: str = ""

    def __init__(self, command: str, ret_code: int, ret_msg: str) -> None:
        self.command = command
        self.ret_code = ret_code
        self.ret_msg = ret_msg
        self.ret_name = ret_name(ret_code)
        msg = f"{command}: {self.ret_name}"
        if ret_msg:
            msg += f": {ret_msg}"
        if self.hint:
            msg += f" ({self.hint})"
        super().__init__(msg)


class GenericCommandError(CommandError):
    code = pb.CMD_ERR


class ParamError(CommandError):
    code = pb.CMD_PARAM_ERR
    hint = "check the arguments against `landscape COMMAND --help`"


class ParamOutOfRangeError(CommandError):
    code = pb.CMD_PARAM_OUT_OF_RANGE_ERR
    hint = "the message names the parameter and its range"


class WrongStateError(CommandError):
    code = pb.CMD_WRONG_STATE_ERR
    hint = "read get-motion-control-state; lock and activate as the command needs"


class NotOwnerError(CommandError):
    code = pb.CMD_NOT_OWNER_ERR
    hint = "only the supervisor that locked may do this: lock first, or wait for the owner to release"


class AddressInUseError(NotOwnerError):
    """connect was refused: another client has a live session on this source address."""

    hint = ("pass another --source-address (Supervisor source_address), or none to let the host pick a free "
            "one")


class BusyError(CommandError):
    code = pb.CMD_BUSY_ERR
    hint = "a previous command is still running; wait for it or stop-motion"


class DeviceTimeoutError(CommandError):
    code = pb.CMD_TIMEOUT_ERR
    hint = "a wait on the device ran out"


class NotConnectedError(CommandError):
    code = pb.CMD_NOT_CONNECTED_ERR
    hint = "the device has no session of this supervisor (its message says why it ended); connect again"


class NotImplementedByDeviceError(CommandError):
    code = pb.CMD_NOT_IMPLEMENTED_ERR
    hint = "this firmware does not implement it yet; see docs/conformance.md"


class UnsupportedError(CommandError):
    code = pb.CMD_UNSUPPORTED_ERR
    hint = "the controller has no such hardware"


class VersionMismatchCommandError(CommandError):
    code = pb.CMD_VERSION_MISMATCH_ERR
    hint = "update the host tool or the firmware so both come from one schema"


class FaultError(CommandError):
    code = pb.CMD_FAULT_ERR
    hint = "a fault is latched; read get-motion-control-state"


class UnknownCommandError(CommandError):
    code = pb.CMD_UNKNOWN_CMD_ERR
    hint = "the firmware's schema lacks this command; update the firmware"


class NoResourcesError(CommandError):
    code = pb.CMD_NO_RESOURCES_ERR
    hint = "a table on the device is full (supervisors, paths, points); free some"


class AuthError(CommandError):
    """The device's policy needs a signed session, or the keys of host and device differ."""

    code = pb.CMD_AUTH_ERR
    hint = "give this host a key of the device's key file: --key-file or LANDSCAPE_KEY_FILE"


class SeqConflictError(CommandError):
    """The device ran another request with this request's seq: another client speaks from this
    address, or frames are forged on the bus (the library has retried once with a fresh seq)."""

    code = pb.CMD_SEQ_CONFLICT_ERR
    hint = "nothing ran: send it again with a fresh seq; pin a --source-address of your own"


_BY_CODE: dict[int, type[CommandError]] = {
    cls.code: cls for cls in (
        GenericCommandError, ParamError, ParamOutOfRangeError, WrongStateError, NotOwnerError,
        BusyError, DeviceTimeoutError, NotConnectedError, NotImplementedByDeviceError,
        UnsupportedError, VersionMismatchCommandError, FaultError, UnknownCommandError,
        NoResourcesError, AuthError, SeqConflictError)
}


def ret_name(code: int) -> str:
    """The RetCode name of a code, or 'RET_<n>' for a code this schema does not know."""
    try:
        return pb.RetCode.Name(code)
    except ValueError:
        return f"RET_{code}"


def error_for_code(command: str, ret_code: int, ret_msg: str) -> CommandError:
    """The CommandError subclass instance for a negative return code."""
    cls = _BY_CODE.get(ret_code, CommandError)
    return cls(command, ret_code, ret_msg)


class ArgumentError(LandscapeError, ValueError):
    """A command was given an argument the schema does not have or cannot hold."""


class KeyFileError(ArgumentError):
    """The host's key file cannot be used: others may read it, a line is not a key, or it lacks
    the key named (docs/host-tool.md "Signed sessions")."""


class SignatureError(LandscapeError):
    """The device's answer does not carry this host's key's signature: the device holds another
    key of that name, or the answer is forged."""
