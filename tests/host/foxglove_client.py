"""A minimal Foxglove WebSocket client for the tests (the `websockets` package, synchronous API).

Speaks what foxglove-sdk's server speaks (subprotocol foxglove.sdk.v1): JSON `serverInfo` and
`advertise` from the server, `subscribe` and `fetchAsset` from the client, binary message data
(opcode 1: subscription id u32, log time u64, payload) and asset responses (opcode 4: request id u32,
status u8, error length u32, error, data), all little-endian.
"""
from __future__ import annotations

import json
import struct
import time
from dataclasses import dataclass, field
from typing import Any

from websockets.sync.client import ClientConnection, connect

from landscape.view import SUBPROTOCOL

OP_MESSAGE_DATA = 0x01
OP_FETCH_ASSET_RESPONSE = 0x04


@dataclass
class Received:
    topic: str
    log_time_ns: int
    payload: bytes

    def json(self) -> dict[str, Any]:
        obj = json.loads(self.payload)
        assert isinstance(obj, dict)
        return obj


@dataclass
class FoxgloveClient:
    url: str
    ws: ClientConnection | None = None
    server_info: dict[str, Any] = field(default_factory=dict)
    channels: dict[str, dict[str, Any]] = field(default_factory=dict)  # topic -> the advertised channel
    _sub_topic: dict[int, str] = field(default_factory=dict)

    def __enter__(self) -> FoxgloveClient:
        self._conn = connect(self.url, subprotocols=[SUBPROTOCOL], open_timeout=5)  # type: ignore[list-item]
        self.ws = self._conn.__enter__()
        return self

    def __exit__(self, *exc: object) -> None:
        self._conn.__exit__(None, None, None)

    def _recv(self, timeout_s: float) -> str | bytes:
        assert self.ws is not None
        return self.ws.recv(timeout=timeout_s)

    def handshake(self, want_channels: int, timeout_s: float = 5.0) -> None:
        """Read serverInfo and advertisements until `want_channels` channels are known."""
        deadline = time.monotonic() + timeout_s
        while not self.server_info or len(self.channels) < want_channels:
            m = self._recv(max(0.01, deadline - time.monotonic()))
            assert isinstance(m, str), f"binary before the advertisements: {m[:20]!r}"
            obj = json.loads(m)
            if obj["op"] == "serverInfo":
                self.server_info = obj
            elif obj["op"] == "advertise":
                self.channels.update({c["topic"]: c for c in obj["channels"]})

    def subscribe(self, *topics: str) -> None:
        assert self.ws is not None
        subs = []
        for i, t in enumerate(topics, start=len(self._sub_topic) + 1):
            subs.append({"id": i, "channelId": self.channels[t]["id"]})
            self._sub_topic[i] = t
        self.ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))

    def messages(self, duration_s: float) -> list[Received]:
        """Message data received within duration_s (other frames are skipped)."""
        out: list[Received] = []
        end = time.monotonic() + duration_s
        while (left := end - time.monotonic()) > 0:
            try:
                m = self._recv(left)
            except TimeoutError:
                break
            if isinstance(m, bytes) and m[0] == OP_MESSAGE_DATA:
                sub, log_time = struct.unpack_from("<IQ", m, 1)
                out.append(Received(self._sub_topic[sub], log_time, bytes(m[13:])))
        return out

    def fetch_asset(self, uri: str, timeout_s: float = 5.0) -> tuple[int, str, bytes]:
        """(status 0 ok / 1 error, error message, data) of fetchAsset(uri)."""
        assert self.ws is not None
        self.ws.send(json.dumps({"op": "fetchAsset", "uri": uri, "requestId": 77}))
        deadline = time.monotonic() + timeout_s
        while True:
            m = self._recv(max(0.01, deadline - time.monotonic()))
            if isinstance(m, bytes) and m[0] == OP_FETCH_ASSET_RESPONSE:
                req, status, n = struct.unpack_from("<IBI", m, 1)
                assert req == 77
                return status, m[10:10 + n].decode(), bytes(m[10 + n:])
