"""What a downlink that did not decode still says: its response's seq and why it failed.

The full decode (landscape_pb2) refuses a message with a text field that is not UTF-8 or a
schema the host does not know; a waiting request must still learn that its answer came and
the user what to do. These read the protobuf wire format itself, top level and nested
length-delimited fields only, and never raise for bytes they cannot read.
"""
from __future__ import annotations

from collections.abc import Iterator


def _varint(data: bytes, i: int) -> tuple[int, int]:
    """A protobuf varint at data[i:]: (value, next index); ValueError when cut short."""
    value = shift = 0
    while i < len(data) and shift < 64:
        b = data[i]
        i += 1
        value |= (b & 0x7F) << shift
        if not b & 0x80:
            return value, i
        shift += 7
    raise ValueError("truncated varint")


def _fields(data: bytes) -> Iterator[tuple[int, int, int | bytes]]:
    """(field number, wire type, value) of the top level of a protobuf message."""
    i = 0
    while i < len(data):
        key, i = _varint(data, i)
        number, wt = key >> 3, key & 7
        if wt == 0:
            v, i = _varint(data, i)
            yield number, wt, v
        elif wt == 2:
            n, i = _varint(data, i)
            if i + n > len(data):
                raise ValueError("truncated field")
            yield number, wt, data[i:i + n]
            i += n
        elif wt in (1, 5):
            i += 8 if wt == 1 else 4
        else:
            raise ValueError(f"wire type {wt}")


def response_seq(data: bytes) -> int | None:
    """The seq of an ls.Downlink carrying a response, read at the wire level (for a
    message the full decode refused), or None."""
    try:
        for number, _wt, value in _fields(data):
            if number == 1 and isinstance(value, bytes):  # Downlink.response
                for n2, wt2, v2 in _fields(value):
                    if n2 == 1 and wt2 == 0 and isinstance(v2, int):  # Response.seq
                        return v2
    except ValueError:
        return None
    return None


def _bad_string(msg: bytes, depth: int = 0) -> str | None:
    """Where a length-delimited field of msg (or of a message inside it) that is
    neither a message nor UTF-8 text goes wrong, or None."""
    for _number, wt, value in _fields(msg):
        if wt != 2 or not isinstance(value, bytes):
            continue
        try:
            value.decode("utf-8")
            continue
        except UnicodeDecodeError as e:
            err = e
        if depth < 4:
            try:
                inner = _bad_string(value, depth + 1)
            except ValueError:
                inner = None
            else:
                if inner is None:
                    continue  # a nested message whose strings are fine
            if inner is not None:
                return inner
        return (f"a text field is not valid UTF-8 at byte {err.start} "
                f"({value[max(0, err.start - 8):err.start + 4]!r})")
    return None


def undecodable_reason(data: bytes, exc: Exception) -> str:
    """Why a downlink did not decode, in words a user can act on."""
    try:
        why = _bad_string(data)
    except ValueError:
        why = None
    if why is not None:
        return f"{why}; the firmware must send UTF-8 text: update it"
    return (f"{exc or 'malformed protobuf'} ({len(data)} bytes): are host tool and firmware built from the "
            f"same schema?")
