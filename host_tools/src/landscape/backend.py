"""Where a CLI command goes: one protocol, two ways.

An invocation of `landscape` sends its commands either through the background session of
its bus and device (`landscape session start`: a SessionClient on a local socket) or, when
none runs, through a session of its own on the bus (a Supervisor). The CLI's code speaks to
either through `Backend` and never asks which one it has.
"""
from __future__ import annotations

from collections.abc import Iterator
from typing import Any, Protocol

from google.protobuf import json_format

from ._generated import landscape_pb2 as pb
from .description import DeviceDescription
from .registry import Command, lookup
from .retval import RetVal
from .session import SessionClient
from .supervisor import Supervisor


class Backend(Protocol):
    """What the CLI needs of a session, the invocation's own or the background one."""

    @property
    def via(self) -> str:
        """"bus" (the invocation's own session) or "session" (the background one), for -v."""

    @property
    def shared(self) -> bool:
        """True for the background session: it outlives this invocation, so a lock taken
        through it stays, and a connection to it is this invocation's to close."""

    def send(self, cmd: Command, fields: dict[str, Any], *, wait_s: float | None) -> RetVal:
        """Send one command; never raises for a negative return code. `wait_s`: the
        background session streams the command's notices up to its final one."""

    def notices(self, timeout_s: float | None = None) -> Iterator[pb.Notice]:
        """The notices as they arrive, until `timeout_s` passes without one."""

    def device_description(self) -> DeviceDescription | None:
        """The device's description (describe), None when it gave none."""

    def confirm_every_rsvp(self) -> None:
        """Answer every RSVP of this session with an accept (the demo goes on); the background
        session answers its RSVPs itself."""

    def close(self) -> None:
        """Let go of this connection (the shared session's); the invocation's own session ends
        with the invocation (CliState.close)."""


def description_of(rv: RetVal) -> DeviceDescription:
    """The DeviceDescription of a describe answer, from our own session or a background one."""
    res = rv.message if isinstance(rv.message, pb.DescribeRes) else \
        json_format.ParseDict(rv.result, pb.DescribeRes())  # through a background session
    return DeviceDescription(res)


class BusBackend:
    """The invocation's own session on the bus."""

    via = "bus"
    shared = False

    def __init__(self, sup: Supervisor) -> None:
        self.sup = sup

    def send(self, cmd: Command, fields: dict[str, Any], *, wait_s: float | None) -> RetVal:
        if cmd.field == "connect":  # the session is connected already: its connect's answer
            assert self.sup.connect_result is not None
            return self.sup.connect_result.retval
        if cmd.field == "disconnect":
            return self.sup.disconnect(check=False)
        return self.sup.request(cmd, check=False, **fields)

    def notices(self, timeout_s: float | None = None) -> Iterator[pb.Notice]:
        return self.sup.notices(timeout_s)

    def device_description(self) -> DeviceDescription | None:
        return self.sup.description

    def confirm_every_rsvp(self) -> None:
        self.sup.on_rsvp(None, lambda n: None)

    def close(self) -> None:
        pass


class SessionBackend:
    """A connection to the background session of this bus and device."""

    via = "session"
    shared = True

    def __init__(self, client: SessionClient) -> None:
        self.client = client

    def send(self, cmd: Command, fields: dict[str, Any], *, wait_s: float | None) -> RetVal:
        return self.client.request(cmd, check=False, wait_s=wait_s, **fields)

    def notices(self, timeout_s: float | None = None) -> Iterator[pb.Notice]:
        return self.client.notices(timeout_s)

    def device_description(self) -> DeviceDescription | None:
        rv = self.send(lookup("describe"), {}, wait_s=None)
        return description_of(rv) if rv.ok else None

    def confirm_every_rsvp(self) -> None:
        pass

    def close(self) -> None:
        self.client.close()
