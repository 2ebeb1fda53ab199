"""The gateway's pure parts: its configuration file (every mistake one clear error), password hashes,
the users it admits, and the OPC UA methods' arguments derived from the schema."""
from __future__ import annotations

import asyncio
import errno
import logging
import socket
import time
from pathlib import Path

import can
import pytest
from asyncua.crypto.permission_rules import UserRole
from google.protobuf.descriptor import FieldDescriptor

from landscape._generated import landscape_pb2 as pb
from landscape.bus import BusSpec
from landscape.errors import ArgumentError
from landscape.gateway import (
    ArgumentShapeError,
    Gateway,
    GatewayUsers,
    PoolExhaustedError,
    _listen_hint,
    argument_of,
    fields_of,
    rsvp_arguments,
)
from landscape.gateway_config import (
    DEFAULT_POOL,
    GatewayConfigError,
    hash_password,
    load_config,
    parse_config,
    verify_password,
)
from landscape.registry import COMMANDS, is_repeated, lookup

ROOT = Path(__file__).resolve().parents[2]


def test_defaults_are_localhost_anonymous_read_only() -> None:
    cfg = load_config(None)
    assert (cfg.host, cfg.port, cfg.allow_anonymous, cfg.security) == ("127.0.0.1", 4840, True, ("None",))
    assert cfg.users == {} and cfg.pool == DEFAULT_POOL and cfg.session_timeout_s == 10.0


def test_a_full_config(tmp_path: Path) -> None:
    (tmp_path / "c.der").write_bytes(b"x")
    (tmp_path / "k.pem").write_bytes(b"x")
    cfg = parse_config(f"""
[server]
host = "0.0.0.0"
port = 4841
security = ["None", "Basic256Sha256_SignAndEncrypt"]
certificate = "c.der"
private_key = "k.pem"
allow_anonymous = false
session_timeout_s = 2.5
[bus]
interface = "slcan"
channel = "/run/landscape/ls0"
[supervisors]
pool = [0xF1, "0xF2"]
heartbeat_period_ms = 100
[users]
op = "{hash_password('pw', iterations=1000)}"
""", "t.toml", base=tmp_path)
    assert cfg.certificate == tmp_path / "c.der" and cfg.pool == (0xF1, 0xF2) and not cfg.allow_anonymous
    assert cfg.session_timeout_s == 2.5
    assert cfg.check_password("op", "pw") and not cfg.check_password("op", "PW") and not cfg.check_password("x", "pw")


@pytest.mark.parametrize("text, says", [
    ("[server\n", "t.toml: not valid TOML"),
    ("[servr]\n", "unknown section [servr]"),
    ("[server]\nprot = 1\n", "[server] has no key 'prot'"),
    ("[server]\nport = 70000\n", "[server] port: 70000 is not a TCP port"),
    ("[server]\nport = \"x\"\n", "[server] port: 'x' is not a TCP port"),
    ("[server]\nsession_timeout_s = 0\n", "[server] session_timeout_s: 0 is not a time-out in seconds, 1..3600"),
    ("[server]\nsession_timeout_s = 3601\n", "session_timeout_s: 3601 is not a time-out"),
    ("[server]\nsession_timeout_s = \"10\"\n", "session_timeout_s: '10' is not a time-out"),
    ("[server]\nsession_timeout_s = true\n", "session_timeout_s: True is not a time-out"),
    ("[server]\nsecurity = [\"Basic128\"]\n", "security: ['Basic128']: write a list of None, Basic256Sha256"),
    ("[server]\nsecurity = [\"Basic256Sha256_SignAndEncrypt\"]\n", "needs the server's certificate"),
    ("[server]\ncertificate = \"nope.der\"\n", "nope.der does not exist"),
    ("[supervisors]\npool = \"0x10-0x20\"\n", "'0x10' is not a supervisor address: use 0xf1..0xfe"),
    ("[supervisors]\npool = \"0xFE-0xF1\"\n", "runs backwards"),
    ("[supervisors]\nheartbeat_period_ms = 5\n", "outside 10..2000"),
    ("[server]\nallow_anonymous = false\n", "t.toml: [server] allow_anonymous = false with no [users] and no "
                                            "[[certificate_users]]: nobody could connect: add a user"),
    ("[users]\nop = \"secret\"\n", "[users] op: not a password hash: write the line that `landscape gateway "
                                   "--hash-password` prints"),
])
def test_every_mistake_is_named(text: str, says: str, tmp_path: Path) -> None:
    with pytest.raises(GatewayConfigError) as exc:
        parse_config(text, "t.toml", base=tmp_path)
    assert says in str(exc.value)
    assert isinstance(exc.value, ArgumentError)  # the CLI exits 2


def test_an_unreadable_file(tmp_path: Path) -> None:
    with pytest.raises(GatewayConfigError, match="cannot read the gateway configuration .*nope.toml"):
        load_config(tmp_path / "nope.toml")


def test_password_hashes_are_salted() -> None:
    a, b = hash_password("pw", iterations=1000), hash_password("pw", iterations=1000)
    assert a != b and verify_password("pw", a) and verify_password("pw", b) and not verify_password("pv", a)


def test_users() -> None:
    cfg = parse_config(f'[users]\nop = "{hash_password("pw", iterations=1000)}"\n')
    users = GatewayUsers(cfg, {b"DER": "mes"})
    anon = users.get_user(None, certificate=b"")
    assert anon is not None and anon.role == UserRole.Anonymous
    op = users.get_user(None, username="op", password="pw")
    assert op is not None and op.role == UserRole.User and op.name == "op"
    assert users.get_user(None, username="op", password="no") is None
    mes = users.get_user(None, certificate=b"DER")
    assert mes is not None and mes.name == "mes" and mes.role == UserRole.User
    cfg.allow_anonymous = False
    assert users.get_user(None) is None


def test_a_refused_session_is_logged_with_its_user_never_the_password(caplog: pytest.LogCaptureFixture) -> None:
    cfg = parse_config(f'[users]\nop = "{hash_password("pw", iterations=1000)}"\n')
    users = GatewayUsers(cfg, {b"DER": "mes"})
    with caplog.at_level(logging.WARNING, logger="landscape.gateway"):
        assert users.get_user(None, username="op", password="s3cret-guess") is None
        assert users.get_user(None, username="mallory", password="hunter2") is None
    text = caplog.text
    assert "refused a session as user 'op'" in text and "refused a session as user 'mallory'" in text
    assert "s3cret-guess" not in text and "hunter2" not in text
    caplog.clear()
    cfg.allow_anonymous = False
    with caplog.at_level(logging.WARNING, logger="landscape.gateway"):
        assert users.get_user(None, certificate=b"OTHER") is None
    assert "refused an anonymous session: allow_anonymous is false" in caplog.text
    assert "[[certificate_users]]" in caplog.text


def test_every_command_field_has_an_argument() -> None:
    for cmd in COMMANDS.values():
        for fd in cmd.fields():
            arg = argument_of(fd)
            assert arg.Name == fd.name
            assert arg.ValueRank == (1 if is_repeated(fd) else -1), fd.full_name
            if fd.type == FieldDescriptor.TYPE_ENUM:
                assert "JOINT_FRAME" in arg.Description.Text or "one of" in arg.Description.Text


def test_method_arguments_become_request_fields() -> None:
    move = lookup("moveAbsolute")
    assert fields_of(move, ["p1", "JOINT_FRAME", [0.1] * 6]) == {"point_name": "p1", "frame": "JOINT_FRAME",
                                                                 "values": [0.1] * 6}
    assert fields_of(move, ["p1", ""]) == {"point_name": "p1"}  # "" leaves an enum absent
    load = lookup("pathLoad")
    got = fields_of(load, ["r", "JOINT_FRAME", "JOINT_MOTION", "ABSOLUTE_DATA", 1, ['{"joints": [0, 0, 0, 0, 0, 0]}']])
    assert got["tags"] == [{"joints": [0, 0, 0, 0, 0, 0]}]
    with pytest.raises(ArgumentError, match=r"pathLoad.tags: '\{bad' is not a JSON object"):
        fields_of(load, ["r", "JOINT_FRAME", "JOINT_MOTION", "ABSOLUTE_DATA", 1, ["{bad"]])
    with pytest.raises(ArgumentError, match="lock takes 0 arguments"):
        fields_of(lookup("lock"), [1])


def test_a_string_is_not_an_array() -> None:
    """"000000" for moveAbsolute's values moved the arm to zeros (one value per character):
    docs/gateway.md "Methods"."""
    move, load = lookup("moveAbsolute"), lookup("pathLoad")
    with pytest.raises(ArgumentShapeError,
                       match=r"moveAbsolute\.values: an array \(Double\[\]\) is expected, got str"):
        fields_of(move, ["p1", "JOINT_FRAME", "000000"])
    with pytest.raises(ArgumentShapeError, match=r"pathLoad\.tags: an array \(String\[\]\) is expected"):
        fields_of(load, ["r", "JOINT_FRAME", "JOINT_MOTION", "ABSOLUTE_DATA", 1, '{"joints": [0, 0, 0, 0, 0, 0]}'])
    assert fields_of(move, ["p1", "JOINT_FRAME", (0.0,) * 6])["values"] == [0.0] * 6


def test_an_unknown_enum_value_names_the_argument() -> None:
    """"SpeedType: 'WARP_SPEED' is not a value" did not say which argument was wrong: docs/gateway.md "Methods"."""
    with pytest.raises(ArgumentError, match=r"^setSpeed\.attribute: 'WARP_SPEED' is not a SpeedType value \(one "
                                            r"of PERCENT_SPEED, LINEAR_SPEED, ANGULAR_SPEED\)$"):
        fields_of(lookup("setSpeed"), [50.0, "WARP_SPEED"])
    # a value of the right shape: the call answers CMD_PARAM_ERR with this text, not BadInvalidArgument
    with pytest.raises(ArgumentError) as err:
        fields_of(lookup("setSpeed"), [50.0, "WARP_SPEED"])
    assert not isinstance(err.value, ArgumentShapeError)
    assert fields_of(lookup("setSpeed"), [50.0, "PERCENT_SPEED"]) == {"speed": 50.0, "attribute": "PERCENT_SPEED"}


def test_answer_rsvp_arguments_are_checked_by_name() -> None:
    assert rsvp_arguments([5, -1, ["why=test"]]) == (5, -1, ["why=test"])
    assert rsvp_arguments([5, 0]) == (5, 0, [])
    for args, says in (([5], "takes RsvpId, RetCode"), ([5, 0, [], "x"], "got 4 arguments"),
                       (["one", 0, []], "AnswerRsvp.RsvpId: an integer"), ([5, True], "AnswerRsvp.RetCode"),
                       ([-1, 0], "AnswerRsvp.RsvpId: -1 is outside"), ([5, 0, "why"], "AnswerRsvp.Data: an array")):
        with pytest.raises(ArgumentError, match=says):
            rsvp_arguments(args)


def test_a_listen_failure_gets_the_hint_that_fits() -> None:
    assert "another program listens" in _listen_hint(OSError(errno.EADDRINUSE, "in use"))
    assert "not an address of this machine" in _listen_hint(OSError(errno.EADDRNOTAVAIL, "cannot assign"))
    assert "not an address of this machine" in _listen_hint(socket.gaierror(socket.EAI_NONAME, "unknown"))


def test_the_shipped_config_parses() -> None:
    cfg = load_config(ROOT / "firmware" / "app" / "deploy" / "gateway.toml")
    assert cfg.host == "127.0.0.1" and not cfg.users


def test_a_full_pool_says_which_addresses_are_held_and_heard() -> None:
    """No address left: the error names the gateway's own, those another supervisor beats from, and
    what to do, so an operator can tell a busy gateway from an address clash on the bus."""
    cfg = parse_config('[supervisors]\npool = ["0xF7", "0xF8", "0xF9"]\n', "test.toml")
    gw = Gateway(cfg, BusSpec("virtual", "pool-test"))
    bus = can.Bus(interface="virtual", channel="pool-test")
    notifier = can.Notifier(bus, [], timeout=0.05)
    try:
        gw._bus, gw._notifier = bus, notifier
        gw._used = {0xF7}
        gw._heard = {0xF8: time.monotonic(), 0xF9: time.monotonic()}
        with pytest.raises(PoolExhaustedError) as err:
            asyncio.run(gw._open_supervisor(0x10, "t"))
    finally:
        notifier.stop()
        bus.shutdown()
    assert err.value.ret_code == pb.CMD_NO_RESOURCES_ERR  # a shortage, as the device's own table-full refusal
    msg = str(err.value)
    assert "held by this gateway: 0xf7 (a session)" in msg, msg
    assert "another supervisor: 0xf8, 0xf9" in msg, msg
    assert "refused by the controller as in use: none" in msg, msg
    assert "widen [supervisors] pool" in msg, msg


def test_the_log_names_a_session_by_its_clients_address_and_user() -> None:
    """asyncua names a session by its peer (host, port): the log shows it as host:port and the user."""
    from types import SimpleNamespace

    from landscape.gateway import _label

    alice = SimpleNamespace(name=("127.0.0.1", 60740), user=SimpleNamespace(name="alice", role=UserRole.User))
    anon = SimpleNamespace(name=("::1", 4841, 0, 0), user=SimpleNamespace(name=None, role=UserRole.Anonymous))
    other = SimpleNamespace(name="Session1", user=SimpleNamespace(name=None, role=UserRole.User))
    assert _label(alice) == "127.0.0.1:60740 (alice)"  # type: ignore[arg-type]
    assert _label(anon) == "::1:4841 (anonymous)"  # type: ignore[arg-type]
    assert _label(other) == "Session1 (user)"  # type: ignore[arg-type]
