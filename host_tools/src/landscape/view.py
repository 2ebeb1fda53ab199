"""A live Foxglove view: the channels of an MCAP recording (mcap_log.py), served on a Foxglove WebSocket.

`LiveView` is a mcap_log.ChannelWriter whose sink is a Foxglove WebSocket server (PyPI `foxglove-sdk`):
the same topics, schemas (byte for byte, `channel_schemas`) and JSON messages as `landscape record
FILE.mcap` writes, published as they arrive. It also serves the arm's URDF as an asset at URDF_URI, so a
3D panel of a live connection loads it without a file (the device's own, see `use_robot`);
`data/foxglove-layout.json` (LAYOUT_NAME) is a Foxglove layout of the 3D arm, joint plots and the notices
that names only these topics.

The server listens on 127.0.0.1 by default: only this machine's programs connect. It carries what the
bus carries; it takes no commands (no client publishing, no services).
"""
from __future__ import annotations

import threading
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .errors import LandscapeError
from .mcap_log import ChannelWriter, channel_schemas
from .urdf import ArmChain, urdf_text

if TYPE_CHECKING:
    import foxglove
    import foxglove.websocket

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 8765  # Foxglove's own default for its WebSocket connections
URDF_URI = "package://landscape/robot.urdf"  # the device's URDF (use_robot), the layout's 3D panel loads it
LAYOUT_NAME = "foxglove-layout.json"
SUBPROTOCOL = "foxglove.sdk.v1"  # what foxglove-sdk's server speaks (the app and the test client ask for it)


class ViewError(LandscapeError):
    """The live view cannot start (the port is taken, foxglove-sdk is missing)."""


def layout_text() -> str:
    """The Foxglove layout shipped with the package (Layouts > Import from file)."""
    return resources.files("landscape").joinpath("data", LAYOUT_NAME).read_text(encoding="utf-8")


def write_layout(path: str | Path) -> Path:
    p = Path(path)
    try:
        p.write_text(layout_text(), encoding="utf-8")
    except OSError as exc:
        raise ViewError(f"cannot write {p}: {exc.strerror or exc}") from None
    return p


def _foxglove() -> Any:
    try:
        import foxglove
    except ImportError:
        raise ViewError("the live view needs the Python package foxglove-sdk: pip install 'landscape[view]' "
                        "(in a checkout: bash .ci/setup)") from None
    return foxglove


class _Listener:
    """Counts the clients that subscribe to at least one channel (foxglove.websocket.ServerListener)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._subs: dict[int, set[int]] = {}
        self.seen: set[int] = set()

    def on_subscribe(self, client: Any, channel: Any) -> None:
        with self._lock:
            self._subs.setdefault(int(client.id), set()).add(int(channel.id))
            self.seen.add(int(client.id))

    def on_unsubscribe(self, client: Any, channel: Any) -> None:
        with self._lock:
            subs = self._subs.get(int(client.id))
            if subs is not None:
                subs.discard(int(channel.id))
                if not subs:
                    del self._subs[int(client.id)]

    @property
    def clients(self) -> int:
        with self._lock:
            return len(self._subs)


class LiveView(ChannelWriter):
    """Publishes the channels of mcap_log on a Foxglove WebSocket server at ws://host:port (port 0: a free
    one, see `port`). Feed it like a McapRecorder (broadcast, notice, frame); close() stops the server."""

    def __init__(self, *, host: str = DEFAULT_HOST, port: int = DEFAULT_PORT, name: str = "landscape",
                 start_s: float | None = None, chain: ArmChain | None = None) -> None:
        fg = _foxglove()
        super().__init__(start_s=start_s, chain=chain)
        self.host = host
        self._urdf = urdf_text().encode()
        self._ctx: foxglove.Context = fg.Context()
        self._channels: dict[str, foxglove.Channel] = {
            topic: fg.Channel(topic, schema=fg.Schema(name=schema, encoding="jsonschema", data=data),
                              message_encoding="json", context=self._ctx)
            for topic, schema, data in channel_schemas()}
        self.listener = _Listener()
        try:
            self._server: foxglove.websocket.WebSocketServer = fg.start_server(
                name=name, host=host, port=port, context=self._ctx, server_listener=self.listener,
                asset_handler=self._asset)
        except RuntimeError as exc:  # foxglove-sdk raises RuntimeError("FoxgloveError: Failed to bind port: ...")
            for ch in self._channels.values():
                ch.close()
            why = str(exc).removeprefix("FoxgloveError: ")
            hint = ("another program listens there (another `landscape view`?): pass --port N, or --port 0 for a "
                    "free one") if "in use" in why.lower() else "check --host and --port"
            raise ViewError(f"cannot serve the live view on {host}:{port}: {why}: {hint}") from None
        self.port: int = int(self._server.port)

    def __enter__(self) -> LiveView:
        return self

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"ws://{host}:{self.port}"

    @property
    def clients(self) -> int:
        """Clients subscribed to at least one channel now."""
        return self.listener.clients

    def use_robot(self, urdf: str) -> None:
        super().use_robot(urdf)
        self._urdf = urdf.encode()

    def _asset(self, uri: str) -> bytes | None:
        return self._urdf if uri == URDF_URI else None

    def _write(self, topic: str, ns: int, data: bytes, sequence: int) -> None:
        self._channels[topic].log(data, log_time=ns)

    def _finish(self) -> None:
        self._server.stop()
        for ch in self._channels.values():
            ch.close()

