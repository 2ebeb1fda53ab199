"""A live Foxglove view: the channels of an MCAP recording (mcap_log.py), served on a Foxglove WebSocket.

`LiveView` is a mcap_log.ChannelWriter whose sink is a Foxglove WebSocket server (PyPI `foxglove-sdk`):
the same topics, schemas (byte for byte, `channel_schemas`) and JSON messages as `landscape record
FILE.mcap` writes, published as they arrive. It also serves the arm's URDF as an asset at URDF_URI, so a
3D panel of a live connection loads it without a file (the device's own, see `use_robot`);
`data/foxglove-layout.json` (LAYOUT_NAME) is a Foxglove layout of the 3D arm, joint plots and the notices
that names only these topics.

The server listens on 127.0.0.1 by default: only this machine's programs connect. It carries what the
bus carries; it takes no commands (no client publishing, no services). A viewer may ask for either name
of the Foxglove WebSocket protocol (SUBPROTOCOLS): foxglove-sdk's server listens on a free loopback port
and the view's own port relays each connection to it, frame by frame, unchanged.
"""
from __future__ import annotations

import asyncio
import os
import threading
from http import HTTPStatus
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .errors import LandscapeError
from .mcap_log import ChannelWriter, channel_schemas
from .urdf import ArmChain, urdf_text

if TYPE_CHECKING:
    import foxglove
    import foxglove.websocket
    from websockets.asyncio.server import Server, ServerConnection
    from websockets.http11 import Request, Response

DEFAULT_HOST = "127.0.0.1"
LOOPBACK = "127.0.0.1"  # where foxglove-sdk's own server listens, behind the relay
DEFAULT_PORT = 8765  # Foxglove's own default for its WebSocket connections
URDF_URI = "package://landscape/robot.urdf"  # the device's URDF (use_robot), the layout's 3D panel loads it
LAYOUT_NAME = "foxglove-layout.json"
SUBPROTOCOL = "foxglove.sdk.v1"  # what foxglove-sdk's server speaks (the app and the test client ask for it)
#: The same protocol under its first name (Foxglove's ws-protocol spec), which Lichtblick and Foxglove
#: releases before the SDK ask for; foxglove-sdk's server answers it with HTTP 400, so the view serves
#: both names on its port and relays each connection to that server (_Relay).
LEGACY_SUBPROTOCOL = "foxglove.websocket.v1"
SUBPROTOCOLS = (SUBPROTOCOL, LEGACY_SUBPROTOCOL)


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


def _bind_error(host: str, port: int, why: str) -> ViewError:
    hint = ("another program listens there (another `landscape view`?): pass --port N, or --port 0 for a "
            "free one") if "in use" in why.lower() else "check --host and --port"
    return ViewError(f"cannot serve the live view on {host}:{port}: {why}: {hint}")


class _Relay:
    """The view's port: a WebSocket server that accepts a client asking for either name of the protocol
    (SUBPROTOCOLS), opens a connection of its own to foxglove-sdk's server at `upstream` and passes every
    message both ways unchanged, until either side closes. Its asyncio loop runs in a thread of its own;
    a client that asks for neither name gets HTTP 400, as from foxglove-sdk's server."""

    def __init__(self, host: str, port: int, upstream: str) -> None:
        try:
            import websockets.asyncio.server  # noqa: F401  (a dependency of the view extra)
        except ImportError:
            raise ViewError("the live view needs the Python package websockets: pip install 'landscape[view]' "
                            "(in a checkout: bash .ci/setup)") from None
        self._upstream = upstream
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_forever, name="landscape-view-relay", daemon=True)
        self._thread.start()
        try:
            self._server: Server = asyncio.run_coroutine_threadsafe(self._serve(host, port), self._loop).result()
        except OSError as exc:
            self._stop_loop()
            # asyncio's text names the address again: the errno's own text is enough
            raise _bind_error(host, port, os.strerror(exc.errno) if exc.errno else str(exc)) from None
        self.port = int(self._server.sockets[0].getsockname()[1])

    async def _serve(self, host: str, port: int) -> Server:
        from websockets.asyncio.server import serve

        return await serve(self._relay, host, port, subprotocols=list(SUBPROTOCOLS),  # type: ignore[arg-type]
                           process_request=self._check, compression=None, max_size=None)

    @staticmethod
    def _check(conn: ServerConnection, request: Request) -> Response | None:
        asked = {p.strip() for p in request.headers.get("Sec-WebSocket-Protocol", "").split(",")}
        if asked & set(SUBPROTOCOLS):
            return None
        return conn.respond(HTTPStatus.BAD_REQUEST, f"ask for subprotocol {' or '.join(SUBPROTOCOLS)}\n")

    async def _relay(self, down: ServerConnection) -> None:
        from websockets.asyncio.client import connect
        from websockets.exceptions import WebSocketException

        async def pump(src: Any, dst: Any) -> None:
            try:
                async for msg in src:
                    await dst.send(msg)
            except (OSError, WebSocketException):
                pass  # either side went away: the other one closes with it

        try:
            async with connect(self._upstream, subprotocols=[SUBPROTOCOL],  # type: ignore[list-item]
                               compression=None, max_size=None) as up:
                tasks = [asyncio.ensure_future(pump(down, up)), asyncio.ensure_future(pump(up, down))]
                _, pending = await asyncio.wait(tasks, return_when=asyncio.FIRST_COMPLETED)
                for t in pending:
                    t.cancel()
        except (OSError, WebSocketException):
            pass  # foxglove-sdk's server is gone (the view is closing): the client's connection closes

    def _stop_loop(self) -> None:
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(timeout=5)
        self._loop.close()

    def close(self) -> None:
        async def shut() -> None:
            self._server.close()
            await self._server.wait_closed()

        asyncio.run_coroutine_threadsafe(shut(), self._loop).result(timeout=10)
        self._stop_loop()


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
        # foxglove-sdk's server on a free loopback port, reached through the relay on the view's port
        try:
            self._server: foxglove.websocket.WebSocketServer = fg.start_server(
                name=name, host=LOOPBACK, port=0, context=self._ctx, server_listener=self.listener,
                asset_handler=self._asset)
            self._relay = _Relay(host, port, f"ws://{LOOPBACK}:{int(self._server.port)}")
        except (RuntimeError, ViewError) as exc:  # foxglove-sdk: RuntimeError("FoxgloveError: ...")
            if not isinstance(exc, RuntimeError):
                self._server.stop()
            for ch in self._channels.values():
                ch.close()
            if isinstance(exc, ViewError):
                raise
            raise _bind_error(LOOPBACK, 0, str(exc).removeprefix("FoxgloveError: ")) from None
        self.port: int = self._relay.port

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
        self._relay.close()
        self._server.stop()
        for ch in self._channels.values():
            ch.close()

