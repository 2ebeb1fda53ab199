"""Single-frame broadcasts described by protocol/landscape.dbc (via cantools).

Ids in the DBC carry the default device address in their low byte; frames on
the bus carry their sender's address there, so matching is on id & 0x1FFFFF00.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from typing import Any

import can
import cantools.database
from cantools.database.can import Database as DbcDatabase
from cantools.database.can import Message as DbcMessage

from .errors import ArgumentError

ID_MASK = 0x1FFFFF00


@lru_cache(maxsize=1)
def database() -> DbcDatabase:
    """The telemetry DBC shipped with the package (a copy of protocol/landscape.dbc)."""
    text = resources.files("landscape._generated").joinpath("landscape.dbc").read_text()
    db = cantools.database.load_string(text, database_format="dbc")
    if not isinstance(db, DbcDatabase):  # a "dbc" load is always a CAN database
        raise TypeError(f"landscape.dbc loaded as {type(db).__name__}, not a CAN database")
    return db


@lru_cache(maxsize=1)
def _by_base() -> dict[int, DbcMessage]:
    return {m.frame_id & ID_MASK: m for m in database().messages}


def frame_id(name: str, sender: int) -> int:
    """29-bit CAN id of broadcast `name` sent by node `sender`."""
    return (database().get_message_by_name(name).frame_id & ID_MASK) | (sender & 0xFF)


def encode(name: str, sender: int, **signals: float) -> can.Message:
    """A broadcast frame; signals not given are 0."""
    msg = database().get_message_by_name(name)
    mux = next((s for s in msg.signals if s.is_multiplexer), None)
    selector = signals.get(mux.name, 0) if mux is not None else None
    # a multiplexed message (HEARTBEAT, by hb_role) carries the signals of its selector only
    values: dict[str, float] = {s.name: 0 for s in msg.signals
                                if s.multiplexer_ids is None or selector in s.multiplexer_ids}
    values.update(signals)
    return can.Message(arbitration_id=frame_id(name, sender), is_extended_id=True,
                       data=msg.encode(values), dlc=msg.length)


@dataclass
class Broadcast:
    name: str
    sender: int
    signals: dict[str, Any]
    timestamp: float = field(default_factory=time.monotonic)


def choice_name(message: str, signal: str, value: int) -> str:
    """The DBC's name for `value` of an enumerated signal (its VAL_ table), or the
    number itself when the table has no such entry."""
    choices: dict[int, object] = dict(database().get_message_by_name(message).get_signal_by_name(signal).choices or {})
    name = choices.get(value)
    return str(name) if name is not None else str(value)


def choice_value(message: str, signal: str, name: str) -> int:
    """The number the DBC's value table (VAL_) of `signal` of broadcast `message` gives
    `name`, e.g. choice_value("STATUS", "st_motion", "robot_stopping"): code that compares
    or sends a status code names it, the DBC holds the number. ArgumentError naming the
    known names when the table has no such name."""
    choices: dict[int, object] = dict(database().get_message_by_name(message).get_signal_by_name(signal).choices or {})
    for value, text in choices.items():
        if str(text) == name:
            return int(value)
    known = ", ".join(str(t) for t in choices.values()) or "none: the signal has no value table"
    raise ArgumentError(f"{message}.{signal} has no value named {name!r} in landscape.dbc (known: {known})")


def cycle_time_s(message: str) -> float:
    """The period at which the device sends broadcast `message`, from the DBC's
    GenMsgCycleTime (s). ArgumentError when the DBC gives the message none."""
    ms = database().get_message_by_name(message).cycle_time
    if not ms:
        raise ArgumentError(f"{message} has no GenMsgCycleTime in landscape.dbc: it is not sent periodically")
    return ms / 1000.0


def decode(frame: can.Message) -> Broadcast | None:
    """The broadcast carried by `frame`, or None when it is not one of the DBC's."""
    if not frame.is_extended_id or frame.is_error_frame or frame.is_remote_frame:
        return None
    msg = _by_base().get(frame.arbitration_id & ID_MASK)
    if msg is None or len(frame.data) < msg.length:
        return None
    try:
        signals = msg.decode(bytes(frame.data[:msg.length]), decode_choices=False)
    except Exception:
        return None
    if not isinstance(signals, dict):  # a container message's list of parts: the DBC declares none
        return None
    return Broadcast(msg.name, frame.arbitration_id & 0xFF, dict(signals))
