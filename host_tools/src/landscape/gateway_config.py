"""The configuration of `landscape gateway` (docs/gateway.md "Configuration"): a TOML file, checked whole
before anything starts. Every mistake is a GatewayConfigError (an ArgumentError: the CLI exits 2) that
names the file, the key and what to write instead. Pure: nothing here opens a socket or the bus.

Passwords are stored as PBKDF2-SHA256 hashes (`hash_password`, `landscape gateway --hash-password`),
never in clear text.
"""
from __future__ import annotations

import hashlib
import hmac
import secrets
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ._generated import landscape_pb2 as pb
from .auth import SupervisorKey, load_key
from .bus import DEFAULT_HEARTBEAT_PERIOD_MS
from .errors import ArgumentError, KeyFileError

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 4840  # the IANA port of OPC UA's binary protocol (opc.tcp)
DEFAULT_CONFIG = Path("/etc/landscape/gateway.toml")
#: The gateway's supervisors speak from the upper part of the hosts' pool by default, so the CLI's
#: sessions (which take the lowest free address) and the gateway's rarely meet.
DEFAULT_POOL: tuple[int, ...] = tuple(range(pb.HOST_ADDRESS_POOL_LAST - 7, pb.HOST_ADDRESS_POOL_LAST + 1))
HOST_POOL_RANGE = range(pb.DEFAULT_HOST_ADDRESS, pb.HOST_ADDRESS_POOL_LAST + 1)
PBKDF2_ITERATIONS = 200_000
SECURITY_POLICIES = ("None", "Basic256Sha256_SignAndEncrypt")


class GatewayConfigError(ArgumentError):
    """The gateway's configuration is unusable (the message says where and what to write)."""


@dataclass(frozen=True)
class CertificateUser:
    name: str
    certificate: Path


@dataclass
class GatewayConfig:
    host: str = DEFAULT_HOST
    port: int = DEFAULT_PORT
    security: tuple[str, ...] = ("None",)
    certificate: Path | None = None
    private_key: Path | None = None
    allow_anonymous: bool = True
    session_timeout_s: float = 10.0
    interface: str | None = None
    channel: str | None = None
    bitrate: int | None = None
    pool: tuple[int, ...] = DEFAULT_POOL
    heartbeat_period_ms: int = DEFAULT_HEARTBEAT_PERIOD_MS
    #: [supervisors] key_file and key_id: the key every supervisor of the gateway signs its sessions
    #: with (docs/protocol.md "Security"); None: unsigned sessions.
    key: SupervisorKey | None = None
    users: dict[str, str] = field(default_factory=dict)  # name -> PBKDF2 hash
    certificate_users: list[CertificateUser] = field(default_factory=list)
    source: str = "defaults"

    def check_password(self, name: str, password: str) -> bool:
        stored = self.users.get(name)
        return stored is not None and verify_password(password, stored)


def hash_password(password: str, *, salt: bytes | None = None, iterations: int = PBKDF2_ITERATIONS) -> str:
    """`pbkdf2_sha256$ITERATIONS$SALT_HEX$HASH_HEX`: what [users] NAME = "..." holds."""
    salt = salt if salt is not None else secrets.token_bytes(16)
    digest = hashlib.pbkdf2_hmac("sha256", password.encode("utf-8"), salt, iterations)
    return f"pbkdf2_sha256${iterations}${salt.hex()}${digest.hex()}"


def verify_password(password: str, stored: str) -> bool:
    _, iterations, salt, digest = stored.split("$")
    got = hashlib.pbkdf2_hmac("sha256", password.encode("utf-8"), bytes.fromhex(salt), int(iterations))
    return hmac.compare_digest(got.hex(), digest)


def _check_hash(where: str, value: object) -> str:
    parts = value.split("$") if isinstance(value, str) else []
    ok = len(parts) == 4 and parts[0] == "pbkdf2_sha256" and parts[1].isdigit()
    if ok:
        try:
            bytes.fromhex(parts[2])
            bytes.fromhex(parts[3])
        except ValueError:
            ok = False
    if not ok:
        raise GatewayConfigError(f"{where}: not a password hash: write the line that `landscape gateway "
                                 f"--hash-password` prints (pbkdf2_sha256$ITERATIONS$SALT$HASH), never the "
                                 f"password itself")
    return str(value)


def _address(where: str, value: object) -> int:
    try:
        a = int(value, 0) if isinstance(value, str) else value
    except ValueError:
        a = None
    if not isinstance(a, int) or isinstance(a, bool) or a not in HOST_POOL_RANGE:
        raise GatewayConfigError(f"{where}: {value!r} is not a supervisor address: use "
                                 f"{HOST_POOL_RANGE[0]:#04x}..{HOST_POOL_RANGE[-1]:#04x} (docs/protocol.md "
                                 f"\"Addresses\")")
    return a


def _pool(where: str, value: object) -> tuple[int, ...]:
    if isinstance(value, str) and "-" in value:
        lo, _, hi = value.partition("-")
        first, last = _address(where, lo.strip()), _address(where, hi.strip())
        if last < first:
            raise GatewayConfigError(f"{where}: {value!r} runs backwards: write LOW-HIGH, e.g. \"0xF7-0xFE\"")
        return tuple(range(first, last + 1))
    if isinstance(value, list) and value:
        out = tuple(_address(f"{where}[{i}]", v) for i, v in enumerate(value))
        if len(set(out)) != len(out):
            raise GatewayConfigError(f"{where}: an address is listed twice")
        return out
    raise GatewayConfigError(f"{where}: write a range \"0xF7-0xFE\" or a list [0xF7, 0xF8]")


_KNOWN: dict[str, set[str]] = {
    "server": {"host", "port", "security", "certificate", "private_key", "allow_anonymous", "session_timeout_s"},
    "bus": {"interface", "channel", "bitrate"},
    "supervisors": {"pool", "heartbeat_period_ms", "key_file", "key_id"},
    "users": set(),
    "certificate_users": set(),
}


def _typed(where: str, value: object, kind: type, what: str) -> Any:
    if not isinstance(value, kind) or (kind is int and isinstance(value, bool)):
        raise GatewayConfigError(f"{where}: {value!r} is not {what}")
    return value


def parse_config(text: str, source: str = "<text>", *, base: Path | None = None) -> GatewayConfig:
    """The configuration in TOML `text` (file name `source`, for messages). Relative paths are
    read from `base` (the file's folder)."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise GatewayConfigError(f"{source}: not valid TOML ({exc}): see docs/gateway.md \"Configuration\"") from None
    cfg = GatewayConfig(source=source)
    for section, value in data.items():
        if section not in _KNOWN:
            raise GatewayConfigError(f"{source}: unknown section [{section}]; known: "
                                     f"{', '.join('[' + s + ']' for s in _KNOWN)}")
        if section == "certificate_users":
            continue
        if not isinstance(value, dict):
            raise GatewayConfigError(f"{source}: {section} must be a table ([{section}])")
        if _KNOWN[section]:
            for key in value:
                if key not in _KNOWN[section]:
                    raise GatewayConfigError(f"{source}: [{section}] has no key {key!r}; known: "
                                             f"{', '.join(sorted(_KNOWN[section]))}")

    def path(where: str, value: object) -> Path:
        p = Path(_typed(where, value, str, "a file name"))
        p = p if p.is_absolute() or base is None else base / p
        if not p.is_file():
            raise GatewayConfigError(f"{where}: {p} does not exist or is not a file")
        return p

    server = data.get("server", {})
    where = f"{source}: [server]"
    if "host" in server:
        cfg.host = _typed(f"{where} host", server["host"], str, "a host name or address")
    if "port" in server:
        cfg.port = _typed(f"{where} port", server["port"], int, "a TCP port")
        if not 0 < cfg.port < 65536:
            raise GatewayConfigError(f"{where} port: {cfg.port} is not a TCP port (1..65535)")
    if "allow_anonymous" in server:
        cfg.allow_anonymous = _typed(f"{where} allow_anonymous", server["allow_anonymous"], bool, "true or false")
    if "session_timeout_s" in server:
        t = server["session_timeout_s"]
        if isinstance(t, bool) or not isinstance(t, (int, float)) or not 1 <= t <= 3600:
            raise GatewayConfigError(f"{where} session_timeout_s: {t!r} is not a time-out in seconds, 1..3600")
        cfg.session_timeout_s = float(t)
    if "security" in server:
        sec = server["security"]
        if not isinstance(sec, list) or not sec or any(s not in SECURITY_POLICIES for s in sec):
            raise GatewayConfigError(f"{where} security: {sec!r}: write a list of {', '.join(SECURITY_POLICIES)}")
        cfg.security = tuple(sec)
    if "certificate" in server:
        cfg.certificate = path(f"{where} certificate", server["certificate"])
    if "private_key" in server:
        cfg.private_key = path(f"{where} private_key", server["private_key"])
    if (cfg.certificate is None) != (cfg.private_key is None):
        raise GatewayConfigError(f"{where}: certificate and private_key go together: give both or neither")
    if "Basic256Sha256_SignAndEncrypt" in cfg.security and cfg.certificate is None:
        raise GatewayConfigError(f"{where} security: Basic256Sha256_SignAndEncrypt needs the server's certificate "
                                 f"and private_key (docs/gateway.md \"Security\" shows how to make them)")

    bus = data.get("bus", {})
    if "interface" in bus:
        cfg.interface = _typed(f"{source}: [bus] interface", bus["interface"], str, "a python-can interface name")
    if "channel" in bus:
        cfg.channel = _typed(f"{source}: [bus] channel", bus["channel"], str, "a channel name")
    if "bitrate" in bus:
        cfg.bitrate = _typed(f"{source}: [bus] bitrate", bus["bitrate"], int, "a bit rate in bit/s")

    sups = data.get("supervisors", {})
    if "pool" in sups:
        cfg.pool = _pool(f"{source}: [supervisors] pool", sups["pool"])
    if "heartbeat_period_ms" in sups:
        hb = _typed(f"{source}: [supervisors] heartbeat_period_ms", sups["heartbeat_period_ms"], int, "milliseconds")
        if not pb.HEARTBEAT_PERIOD_MIN_MS <= hb <= pb.HEARTBEAT_PERIOD_MAX_MS:
            raise GatewayConfigError(f"{source}: [supervisors] heartbeat_period_ms: {hb} is outside "
                                     f"{pb.HEARTBEAT_PERIOD_MIN_MS}..{pb.HEARTBEAT_PERIOD_MAX_MS} "
                                     f"(docs/protocol.md \"Liveness\")")
        cfg.heartbeat_period_ms = hb
    if "key_id" in sups and "key_file" not in sups:
        raise GatewayConfigError(f"{source}: [supervisors] key_id names a key of key_file: give key_file too")
    if "key_file" in sups:
        key_file = path(f"{source}: [supervisors] key_file", sups["key_file"])
        key_id = _typed(f"{source}: [supervisors] key_id", sups["key_id"], str, "a key name") \
            if "key_id" in sups else None
        try:
            cfg.key = load_key(key_file, key_id)
        except KeyFileError as exc:
            raise GatewayConfigError(f"{source}: [supervisors] key_file: {exc}") from None

    for name, value in data.get("users", {}).items():
        cfg.users[name] = _check_hash(f"{source}: [users] {name}", value)
    certs = data.get("certificate_users", [])
    if not isinstance(certs, list):
        raise GatewayConfigError(f"{source}: certificate_users must be an array of tables ([[certificate_users]])")
    for i, entry in enumerate(certs):
        w = f"{source}: [[certificate_users]] #{i + 1}"
        if not isinstance(entry, dict) or set(entry) != {"name", "certificate"}:
            raise GatewayConfigError(f"{w}: write name = \"...\" and certificate = \"FILE.der\"")
        cfg.certificate_users.append(CertificateUser(_typed(f"{w} name", entry["name"], str, "a user name"),
                                                     path(f"{w} certificate", entry["certificate"])))
    if cfg.certificate_users and cfg.certificate is None:
        raise GatewayConfigError(f"{source}: [[certificate_users]] need the server's certificate and private_key "
                                 f"([server]): a user certificate is checked over a signed channel")
    if not cfg.allow_anonymous and not cfg.users and not cfg.certificate_users:
        raise GatewayConfigError(f"{where} allow_anonymous = false with no [users] and no [[certificate_users]]: "
                                 f"nobody could connect: add a user (NAME = the line `landscape gateway "
                                 f"--hash-password` prints) or a [[certificate_users]] entry, or set "
                                 f"allow_anonymous = true")
    return cfg


def load_config(path: Path | None) -> GatewayConfig:
    """The file at `path` (None: the defaults: localhost, anonymous read-only, no users)."""
    if path is None:
        return GatewayConfig()
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise GatewayConfigError(f"cannot read the gateway configuration {path}: {why}") from None
    return parse_config(text, str(path), base=path.parent)
