"""The host's half of signed sessions (docs/protocol.md "Security"): key files, the MAC
framing, and the gateway's key."""
from __future__ import annotations

import hashlib
import hmac
import struct
from pathlib import Path

import pytest

from landscape import auth
from landscape._generated import landscape_pb2 as pb
from landscape.errors import KeyFileError
from landscape.gateway_config import GatewayConfigError, parse_config

KEY = bytes(range(32))


def key_file(tmp_path: Path, text: str, mode: int = 0o600) -> Path:
    p = tmp_path / "host.keys"
    p.write_text(text)
    p.chmod(mode)
    return p


def test_a_key_file_names_its_keys_and_hides_their_bytes(tmp_path: Path) -> None:
    p = key_file(tmp_path, f"# ops\nops = {KEY.hex()}\nbench = {KEY[::-1].hex().upper()}\n")
    k = auth.load_key(p, "bench")
    assert (k.key_id, k.key) == ("bench", KEY[::-1])
    assert KEY.hex() not in repr(auth.load_key(p, "ops"))
    with pytest.raises(KeyFileError, match="holds keys ops, bench: choose one with --key-id"):
        auth.load_key(p)
    with pytest.raises(KeyFileError, match="holds no key 'x'"):
        auth.load_key(p, "x")


@pytest.mark.parametrize("text,mode,message", [
    (f"ops = {KEY.hex()}\n", 0o644, "mode 0644 lets others read the key: chmod 600"),
    (f"ops = {KEY.hex()[:-1]}\n", 0o600, ":1: key 'ops': expected 64 hex digits"),
    (f"ops {KEY.hex()}\n", 0o600, ":1: expected NAME = 64 hex digits"),
    (f"ops = {KEY.hex()}\nops = {KEY.hex()}\n", 0o600, ":2: key 'ops' is given twice"),
    ("# none\n", 0o600, "holds no key"),
])
def test_a_bad_key_file_is_one_line_without_the_key(tmp_path: Path, text: str, mode: int, message: str) -> None:
    with pytest.raises(KeyFileError, match=message) as ei:
        auth.load_key(key_file(tmp_path, text, mode))
    assert KEY.hex()[:16] not in str(ei.value) and "\n" not in str(ei.value)


def test_the_mac_is_the_documented_framing() -> None:
    """docs/protocol.md "The signature", byte for byte, from hmac alone."""
    hn, dn = b"h" * auth.NONCE_BYTES, b"d" * auth.NONCE_BYTES
    ks = auth.session_key(KEY, hn, dn, 0xF1, 0x10)
    assert ks == hmac.new(KEY, b"LS1K" + hn + dn + b"\xf1\x10", hashlib.sha256).digest()
    body = pb.Uplink(request=pb.Request(seq=7, lock=pb.LockReq())).SerializeToString()
    signed = auth.sign(ks, auth.UP, 0xF1, 0x10, 42, body)
    want = hmac.new(ks, b"LS1U\xf1\x10" + struct.pack("<I", 42) + body, hashlib.sha256).digest()[:8]
    assert signed == body + bytes([pb.Uplink.DESCRIPTOR.fields_by_name["mac"].number << 3 | 2, 8]) + want
    assert pb.Uplink.FromString(signed).mac == want  # the MAC is the message's last field
    assert auth.verify(ks, auth.UP, 0xF1, 0x10, 42, signed)
    for bad in (signed[:-1] + bytes([signed[-1] ^ 1]), body, signed[1:]):
        assert not auth.verify(ks, auth.UP, 0xF1, 0x10, 42, bad)
    assert not auth.verify(ks, auth.UP, 0xF1, 0x10, 43, signed)  # another epoch
    assert not auth.verify(ks, auth.DOWN, 0xF1, 0x10, 42, signed)  # the other way
    hb = hmac.new(ks, b"LS1H\xf1" + struct.pack("<IIH", 42, 300, 200), hashlib.sha256).digest()[:3]
    assert auth.heartbeat_mac(ks, 0xF1, 42, 300, 200) == int.from_bytes(hb, "little")


def test_the_gateway_signs_with_its_configured_key(tmp_path: Path) -> None:
    p = key_file(tmp_path, f"gw = {KEY.hex()}\n")
    cfg = parse_config(f'[supervisors]\nkey_file = "{p}"\nkey_id = "gw"\n')
    assert cfg.key is not None and cfg.key.key_id == "gw"
    with pytest.raises(GatewayConfigError, match="key_id names a key of key_file: give key_file too"):
        parse_config('[supervisors]\nkey_id = "gw"\n')
    p.chmod(0o640)
    with pytest.raises(GatewayConfigError, match=r"\[supervisors\] key_file: .*chmod 600"):
        parse_config(f'[supervisors]\nkey_file = "{p}"\n')
