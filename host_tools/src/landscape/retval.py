"""What one command returns (RetVal) and the options every call takes (CallOptions): shared by
the supervisor, its typed commands (landscape.commands) and the background session."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, TypedDict

from google.protobuf.message import Message

from ._generated import landscape_pb2 as pb
from .errors import ret_name
from .registry import Command

Enum = int | str
"""An enum argument: its number, its name (JOINT_FRAME) or its short name (joint)."""

@dataclass
class RetVal:
    """What a command returned (the seed's RetVal plus the result fields)."""

    command: Command
    seq: int
    ret_code: int
    ret_msg: str
    message: Message | None          # the result message, e.g. ls.GetRobotPositionRes
    result: dict[str, Any] = field(default_factory=dict)
    epoch: int = 0                   # the session epoch the device answered in (docs/protocol.md)

    @property
    def name(self) -> str:
        return self.command.name

    def __repr__(self) -> str:
        msg = f", ret_msg={self.ret_msg!r}" if self.ret_msg else ""
        return f"RetVal({self.name} seq={self.seq} {self.ret_name}{msg} result={self.result!r})"

    @property
    def ret_name(self) -> str:
        return ret_name(self.ret_code)

    @property
    def ok(self) -> bool:
        return self.ret_code >= 0

    @property
    def started(self) -> bool:
        """True when a non-blocking command started: wait_complete() waits for its end."""
        return self.ret_code == pb.CMD_STARTED_OK


class CallOptions(TypedDict, total=False):
    check: bool              # raise CommandError for a negative code (default True)
    timeout_s: float | None  # per-try response time-out (default: the command's host_timeout_ms)
