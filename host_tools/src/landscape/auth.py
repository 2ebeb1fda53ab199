"""Signed supervisors (docs/protocol.md "Security"): the host's key and the signature scheme.

A supervisor that holds a key of the device opens a signed session: it asks the device for a
challenge, derives the session key from both sides' nonces and signs its connect with it; from
then on every message both ways ends with a MAC field (``Uplink.mac`` / ``Downlink.mac``) and
every heartbeat carries a MAC in ``hb_token``. The framing here is the firmware's
(firmware/auth/ls_auth.h), built on Python's ``hmac`` and ``hashlib``:

    session key    K_s = HMAC-SHA256(K, "LS1K" | host_nonce | device_nonce | host | device)
    message MAC    HMAC-SHA256(K_s, "LS1U"/"LS1D" | source | target | epoch LE32 | body)[:8]
    heartbeat MAC  HMAC-SHA256(K_s, "LS1H" | source | epoch LE32 | counter LE32 | period_ms LE16)[:3], LE

A key's home is a key file that only its owner may read (``NAME = 64 hex digits`` per line, the
device's format), named by ``--key-file`` / ``LANDSCAPE_KEY_FILE`` or the gateway's
configuration, never a key on a command line. No message of this module carries a key's bytes.
Pure but for reading the key file.
"""
from __future__ import annotations

import hashlib
import hmac
import os
import stat
import struct
from dataclasses import dataclass, field
from pathlib import Path

from ._generated import landscape_pb2 as pb
from .errors import KeyFileError

MAC_BYTES: int = pb.AUTH_MAC_BYTES
NONCE_BYTES: int = pb.AUTH_NONCE_BYTES
KEY_BYTES: int = pb.AUTH_KEY_BYTES
HEARTBEAT_MAC_MASK: int = (1 << pb.AUTH_HEARTBEAT_MAC_BITS) - 1
CHALLENGE_TTL_S: float = pb.AUTH_CHALLENGE_TTL_MS / 1000.0
#: The MAC field: its number in Uplink and Downlink (the same), the tag and length bytes before it.
MAC_FIELD: int = pb.Uplink.DESCRIPTOR.fields_by_name["mac"].number
_TRAILER_HEAD = bytes([MAC_FIELD << 3 | 2, MAC_BYTES])
TRAILER_BYTES = len(_TRAILER_HEAD) + MAC_BYTES
#: The environment's names of the host's key (docs/host-tool.md "Signed sessions").
ENV_KEY_FILE = "LANDSCAPE_KEY_FILE"
ENV_KEY_ID = "LANDSCAPE_KEY_ID"
_KEY_ID_MAX = 31

UP = b"LS1U"
DOWN = b"LS1D"


@dataclass(frozen=True)
class SupervisorKey:
    """One key of a key file: its name (what the challenge names) and its 32 bytes, which its
    repr never shows."""

    key_id: str
    key: bytes = field(repr=False)
    source: str = ""  # where it was read, for messages

    def __post_init__(self) -> None:
        if len(self.key) != KEY_BYTES:
            raise KeyFileError(f"key {self.key_id!r} has {len(self.key)} bytes, not {KEY_BYTES}")


def _check_mode(path: Path) -> None:
    try:
        st = path.stat()
    except OSError as exc:
        raise KeyFileError(f"{path}: {exc.strerror}: the key file named by --key-file or {ENV_KEY_FILE}") from None
    if not stat.S_ISREG(st.st_mode):
        raise KeyFileError(f"{path}: not a regular file: name the key file")
    if st.st_mode & 0o077:
        raise KeyFileError(f"{path}: mode {stat.S_IMODE(st.st_mode):04o} lets others read the key: "
                           f"chmod 600 {path}")


def read_keys(path: Path) -> list[SupervisorKey]:
    """Every key of key file `path`; KeyFileError (one line, naming the file and line, never a
    value) when others may read it or a line is not ``NAME = 64 hex digits``."""
    _check_mode(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise KeyFileError(f"{path}: cannot read it as UTF-8 text ({exc})") from None
    keys: list[SupervisorKey] = []
    for number, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if not line or line[0] in "#;":
            continue
        name, eq, value = (p.strip() for p in line.partition("="))
        if not eq:
            raise KeyFileError(f"{path}:{number}: expected NAME = 64 hex digits (one key per line)")
        if not (0 < len(name) <= _KEY_ID_MAX and all(33 <= ord(c) <= 126 and c not in "=#;" for c in name)):
            raise KeyFileError(f"{path}:{number}: key name {name[:_KEY_ID_MAX]!r}: expected 1..{_KEY_ID_MAX} "
                               f"printable characters without blanks, '=', '#' or ';'")
        try:
            key = bytes.fromhex(value) if len(value) == 2 * KEY_BYTES else b""
        except ValueError:
            key = b""
        if not key:
            raise KeyFileError(f"{path}:{number}: key {name!r}: expected {2 * KEY_BYTES} hex digits "
                               f"({KEY_BYTES} random bytes), got {len(value)} characters")
        if any(k.key_id == name for k in keys):
            raise KeyFileError(f"{path}:{number}: key {name!r} is given twice: keep one")
        keys.append(SupervisorKey(name, key, str(path)))
    if not keys:
        raise KeyFileError(f"{path}: holds no key: add a line NAME = 64 hex digits")
    return keys


def load_key(path: str | Path, key_id: str | None = None) -> SupervisorKey:
    """The key `key_id` of key file `path`, or its only key when `key_id` is None."""
    keys = read_keys(Path(path))
    if key_id is None:
        if len(keys) > 1:
            raise KeyFileError(f"{path} holds keys {', '.join(k.key_id for k in keys)}: choose one with --key-id "
                               f"or {ENV_KEY_ID}")
        return keys[0]
    for k in keys:
        if k.key_id == key_id:
            return k
    raise KeyFileError(f"{path} holds no key {key_id!r} (it holds {', '.join(k.key_id for k in keys)})")


def key_from_environment() -> SupervisorKey | None:
    """The key LANDSCAPE_KEY_FILE (and LANDSCAPE_KEY_ID) name, None when no file is named."""
    path = os.environ.get(ENV_KEY_FILE)
    if not path:
        return None
    return load_key(path, os.environ.get(ENV_KEY_ID) or None)


def session_key(key: bytes, host_nonce: bytes, device_nonce: bytes, host: int, device: int) -> bytes:
    """K_s of a challenge: the key both sides derive from the two nonces."""
    return hmac.new(key, b"LS1K" + host_nonce + device_nonce + bytes([host, device]), hashlib.sha256).digest()


def mac(ks: bytes, direction: bytes, source: int, target: int, epoch: int, body: bytes) -> bytes:
    """The MAC of `body` going `direction` (UP or DOWN) from `source` to `target` in `epoch`."""
    head = direction + bytes([source, target]) + struct.pack("<I", epoch)
    return hmac.new(ks, head + body, hashlib.sha256).digest()[:MAC_BYTES]


def sign(ks: bytes, direction: bytes, source: int, target: int, epoch: int, body: bytes) -> bytes:
    """`body` with its MAC field appended."""
    return body + _TRAILER_HEAD + mac(ks, direction, source, target, epoch, body)


def verify(ks: bytes, direction: bytes, source: int, target: int, epoch: int, message: bytes) -> bool:
    """Whether `message` ends with the MAC field of its body (compared in constant time)."""
    if len(message) < TRAILER_BYTES or message[-TRAILER_BYTES:-MAC_BYTES] != _TRAILER_HEAD:
        return False
    body = message[:-TRAILER_BYTES]
    return hmac.compare_digest(message[-MAC_BYTES:], mac(ks, direction, source, target, epoch, body))


def has_mac(message: bytes) -> bool:
    """Whether `message` ends with a MAC field (signed or forged: verify says which)."""
    return len(message) >= TRAILER_BYTES and message[-TRAILER_BYTES:-MAC_BYTES] == _TRAILER_HEAD


def heartbeat_mac(ks: bytes, source: int, epoch: int, counter: int, period_ms: int) -> int:
    """The 24-bit hb_token of a signed session's heartbeat with full counter `counter`."""
    data = b"LS1H" + bytes([source]) + struct.pack("<IIH", epoch, counter, period_ms)
    return int.from_bytes(hmac.new(ks, data, hashlib.sha256).digest()[:3], "little") & HEARTBEAT_MAC_MASK
