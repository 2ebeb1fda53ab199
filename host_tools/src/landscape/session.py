"""Background sessions: one process holds a session, other invocations use it.

`landscape session start` runs `SessionServer` in a background process: it
keeps one Supervisor open (connect, heartbeat, optionally lock) and listens on
a Unix socket named after the device and the bus (``socket_path``). While it
runs, ordinary invocations for the same bus, device and source address send
their commands through the socket (`SessionClient`), so a lock taken by one
invocation lives on after it exits.

The socket speaks JSON lines. A client sends one object per line; the server
answers one or more lines, the last one terminal:

    {"op": "request", "command": "lock", "fields": {}, "timeout_s": null, "wait_s": null}
        -> {"retval": {"command", "seq", "ret_code", "ret_name", "ret_msg", "result"}}
           then, when the command started and wait_s is a number, {"notice": {...}} per
           notice until its final one, then {"done": true}
    {"op": "status"}    -> {"status": {"pid", "socket", "device", "channel", "source_address",
                                       "connected", "owner", "state", "requests", "started_at"}}
    {"op": "telemetry"} -> {"telemetry": {MESSAGE: {signal: value}}}
    {"op": "watch"}     -> {"broadcast": {"name", "sender", "timestamp", "signals"}} and
                           {"notice": {...}} lines until the client closes the connection
                           ("notices_only": true: the notices alone, for `landscape events`)
    {"op": "stop"}      -> {"stopping": true}, then the server disconnects and exits
    any failure         -> {"error": {"type": "<exception class>", "message": "..."}} (terminal)
"""
from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import logging
import os
import queue
import socket
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from google.protobuf import json_format, message_factory
from google.protobuf.message import Message

from . import errors
from . import telemetry as tm
from ._generated import landscape_pb2 as pb
from .bus import BusSpec, resolve_config
from .errors import ArgumentError, LandscapeError
from .notices import format_notice
from .registry import Command, lookup, message_to_dict
from .retval import RetVal
from .supervisor import Supervisor

log = logging.getLogger("landscape.session")

#: Longest path a Unix socket address holds (sun_path on Linux, with its terminating zero).
MAX_SOCKET_PATH = 107


#: Commands a session sends at once, never queued behind another client's request: whatever
#: runs, a stop from any terminal reaches the device (docs/host-tool.md, "Stopping").
PRIORITY_COMMANDS = frozenset({"stop_motion", "abort_motion", "deactivate"})


class SessionError(LandscapeError):
    """No session runs, or the session process does not answer."""


class SessionGoneError(SessionError):
    """The session process a client talked to went away (it stopped, as it does when its device
    stops answering): a client that held its lock and units must not carry on without them."""


def socket_path(spec: BusSpec, device: int, source_address: int | None) -> Path:
    """Where the session of `device` on the bus of `spec` listens: $XDG_RUNTIME_DIR/landscape-
    <device>-<hash>.sock (else the temp directory). The hash covers the resolved interface and
    channel, the user and the source address the invocation pinned (--source-address), or "auto"
    when it pinned none: a session started without -s is found by every invocation without -s,
    whichever free address it took."""
    cfg = resolve_config(spec, strict=False)
    addr = "auto" if source_address is None else f"{source_address:02x}"
    key = f"{cfg.get('interface')}:{cfg.get('channel')}:{addr}:{os.getuid()}"
    digest = hashlib.sha256(key.encode()).hexdigest()[:12]
    base = os.environ.get("XDG_RUNTIME_DIR") or tempfile.gettempdir()
    return Path(base) / f"landscape-{device:02x}-{digest}.sock"


def _jsonable(value: Any) -> Any:
    if isinstance(value, Message):
        return message_to_dict(value)
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    return value


def retval_to_dict(rv: RetVal) -> dict[str, Any]:
    return {"command": rv.command.field, "seq": rv.seq, "ret_code": rv.ret_code, "ret_name": rv.ret_name,
            "ret_msg": rv.ret_msg, "result": rv.result, "epoch": rv.epoch}


def retval_from_dict(d: dict[str, Any]) -> RetVal:
    cmd = lookup(d["command"])
    msg: Message | None = None
    if d["ret_code"] >= 0 or d.get("result"):
        msg = message_factory.GetMessageClass(cmd.response_type)()
        json_format.ParseDict(d.get("result") or {}, msg)
    return RetVal(cmd, int(d["seq"]), int(d["ret_code"]), str(d["ret_msg"]), msg, dict(d.get("result") or {}),
                  int(d.get("epoch", 0)))


def error_from_dict(d: dict[str, Any]) -> LandscapeError:
    cls = SessionGoneError if d.get("type") == SessionGoneError.__name__ else getattr(errors, str(d.get("type")), None)
    message = str(d.get("message", "the session process failed"))
    if isinstance(cls, type) and issubclass(cls, LandscapeError) and not issubclass(cls, errors.CommandError) \
            and cls is not errors.AlarmError:
        return cls(message)
    return LandscapeError(message)


# ---------------------------------------------------------------- server


class SessionServer:
    """Serves one open Supervisor on a Unix socket until stop() or a "stop" request.

    Requests from every client are executed one at a time (a lock), each with the
    session's own seq; notices go to the client waiting for its command's end."""

    def __init__(self, sup: Supervisor, path: Path, *, channel: str = "", link_url: str | None = None) -> None:
        if len(os.fsencode(str(path))) > MAX_SOCKET_PATH:
            raise ArgumentError(f"session socket path {path} is longer than {MAX_SOCKET_PATH} bytes: set "
                                f"XDG_RUNTIME_DIR to a shorter directory")
        self.sup = sup
        self.path = path
        self.channel = channel
        self.link_url = link_url
        self.requests = 0
        self.started_at = time.time()
        self._cmd_lock = threading.Lock()
        self._stop = threading.Event()
        self._sock: socket.socket | None = None

    def bind(self) -> None:
        """Create the socket file (only the user may connect)."""
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        old = os.umask(0o177)
        try:
            sock.bind(str(self.path))
        finally:
            os.umask(old)
        sock.listen(8)
        sock.settimeout(0.2)
        self._sock = sock

    def serve_forever(self) -> None:
        """Accept clients until stopped; removes the socket file on the way out."""
        if self._sock is None:
            self.bind()
        assert self._sock is not None
        self.sup.on_notice(self._log_notice)
        try:
            while not self._stop.is_set():
                why = self.sup.link_problem()
                if why is not None:
                    # The device is gone: every waiting client gets the error (their loops check
                    # it too), then the session ends, so no later invocation uses a dead session.
                    log.error("%s; the session stops", self.sup._link_lost_error(why))
                    time.sleep(0.5)
                    self.stop()
                    break
                try:
                    conn, _ = self._sock.accept()
                except TimeoutError:
                    continue
                except OSError:
                    if self._stop.is_set():
                        break
                    raise
                threading.Thread(target=self._client, args=(conn,), daemon=True,
                                 name="landscape-session-client").start()
        finally:
            with contextlib.suppress(ValueError):
                self.sup.remove_notice_callback(self._log_notice)
            self._sock.close()
            with contextlib.suppress(FileNotFoundError):
                self.path.unlink()

    @staticmethod
    def _log_notice(n: pb.Notice) -> None:
        """Every notice the session receives goes to its log (the final notices of --no-wait
        moves included, which no client may be waiting for)."""
        log.info("notice %s", format_notice(n))

    def stop(self) -> None:
        self._stop.set()

    def status(self) -> dict[str, Any]:
        """The session's description; owner and state as the device answers them now
        (getMotionControlState), else from its last HEARTBEAT, else None."""
        sup = self.sup
        owner: bool | None = None
        state: str | None = None
        if sup.connected:
            with self._cmd_lock:
                try:
                    rv = sup.get_motion_control_state(check=False, timeout_s=1.0)
                    if rv.ok:
                        owner, state = bool(rv.result.get("owner")), str(rv.result.get("state"))
                except LandscapeError:
                    pass
        if state is None:
            hb = sup.telemetry().get("HEARTBEAT", {})
            if hb:
                owner = int(hb.get("hb_owner", -1)) == sup.source_address
                value = int(hb.get("hb_state", -1))
                state = pb.State.Name(value) if value in pb.State.values() else None
        info = sup.device_info
        return {"pid": os.getpid(), "socket": str(self.path), "device": sup.device, "channel": self.channel,
                "source_address": sup.source_address, "connected": sup.connected, "owner": owner, "state": state,
                "device_name": info.device_name if info is not None else None,
                "requests": self.requests, "started_at": self.started_at, "link": self.link_url}

    # ------------------------------------------------------------ one client

    def _client(self, conn: socket.socket) -> None:
        send_lock = threading.Lock()

        def send(obj: dict[str, Any]) -> None:
            data = (json.dumps(obj) + "\n").encode()
            with send_lock:
                conn.sendall(data)

        with conn, conn.makefile("r", encoding="utf-8") as rf:
            try:
                for line in rf:
                    if not line.strip():
                        continue
                    try:
                        obj = json.loads(line)
                        if not isinstance(obj, dict):
                            raise ArgumentError("each line must be a JSON object")
                        self._check_alive()
                        if obj.get("op") == "watch":
                            self._watch(conn, send, notices_only=bool(obj.get("notices_only")))
                            return
                        self._handle(obj, send)
                    except (LandscapeError, ValueError, KeyError, TypeError) as exc:
                        send({"error": {"type": type(exc).__name__, "message": str(exc)}})
                    if self._stop.is_set():
                        return
            except (OSError, ValueError):
                return  # the client went away

    def _check_alive(self) -> None:
        """A request that meets the session on its way out (its device gone, or stopped) gets
        why, never what the closed Supervisor would say of a session not opened."""
        why = self.sup.link_problem()
        if why is not None:
            raise self.sup._link_lost_error(why)
        if self._stop.is_set():
            raise SessionGoneError(f"the background session at {self.path} is stopping (`landscape session "
                                   f"stop`, or its device stopped answering): start it again")

    def _handle(self, obj: dict[str, Any], send: Callable[[dict[str, Any]], None]) -> None:
        op = obj.get("op")
        if op == "status":
            send({"status": self.status()})
        elif op == "telemetry":
            send({"telemetry": self.sup.telemetry()})
        elif op == "stop":
            send({"stopping": True})
            self.stop()
        elif op == "request":
            self._request(obj, send)
        else:
            raise ArgumentError(f"unknown op {op!r}: use request, status, telemetry, watch or stop")

    def _request(self, obj: dict[str, Any], send: Callable[[dict[str, Any]], None]) -> None:
        cmd = lookup(str(obj["command"]))
        fields = obj.get("fields") or {}
        if not isinstance(fields, dict):
            raise ArgumentError("fields must be a JSON object")
        timeout_s = obj.get("timeout_s")
        wait_s = obj.get("wait_s")
        sup = self.sup
        log.info("request %s %s", cmd.name, json.dumps(fields, default=str))
        if cmd.field in ("connect", "disconnect"):
            with self._cmd_lock:
                self.requests += 1
                if cmd.field == "connect":
                    if not sup.connected:
                        sup.connect()
                    assert sup.connect_result is not None
                    rv = sup.connect_result.retval
                else:
                    rv = sup.disconnect(check=False)
            send({"retval": retval_to_dict(rv)})
            send({"done": True})
            return
        # Notices are collected from before the request goes out, so none is lost between
        # its answer and the wait below; the wait holds no lock, so other clients' commands
        # (a stop above all) run while this one's move goes on.
        q: queue.Queue[pb.Notice] = queue.Queue(maxsize=10000)

        def on_n(n: pb.Notice) -> None:
            with contextlib.suppress(queue.Full):
                q.put_nowait(n)

        if wait_s is not None:
            sup.on_notice(on_n)
        try:
            if cmd.field in PRIORITY_COMMANDS:
                rv = self._send_request(cmd, fields, timeout_s)   # never queued behind another client
            else:
                with self._cmd_lock:
                    rv = self._send_request(cmd, fields, timeout_s)
            send({"retval": retval_to_dict(rv)})
            log.info("answer %s seq %d %s %s", cmd.name, rv.seq, rv.ret_name, rv.ret_msg)
            if rv.started and wait_s is not None:
                deadline = time.monotonic() + float(wait_s)
                while not self._stop.is_set():
                    sup.check_link()  # LinkLostError: the client gets it as its terminal line
                    left = deadline - time.monotonic()
                    if left <= 0:
                        break
                    try:
                        n = q.get(timeout=min(left, 0.2))
                    except queue.Empty:
                        continue
                    send({"notice": message_to_dict(n)})
                    if n.final and n.ref_seq == rv.seq and n.session_epoch == rv.epoch:
                        break
            send({"done": True})
        finally:
            if wait_s is not None:
                with contextlib.suppress(ValueError):
                    sup.remove_notice_callback(on_n)

    def _send_request(self, cmd: Command, fields: dict[str, Any], timeout_s: float | None) -> RetVal:
        sup = self.sup
        self.requests += 1
        if not sup.connected:
            with self._cmd_lock if cmd.field in PRIORITY_COMMANDS else contextlib.nullcontext():
                if not sup.connected:
                    sup.connect()
        return sup.request(cmd, check=False, timeout_s=timeout_s, **fields)

    def _watch(self, conn: socket.socket, send: Callable[[dict[str, Any]], None], *,
               notices_only: bool = False) -> None:
        q: queue.Queue[dict[str, Any]] = queue.Queue(maxsize=10000)

        def on_b(b: tm.Broadcast) -> None:
            with contextlib.suppress(queue.Full):
                q.put_nowait({"broadcast": {"name": b.name, "sender": b.sender, "timestamp": b.timestamp,
                                            "signals": b.signals}})

        def on_n(n: pb.Notice) -> None:
            with contextlib.suppress(queue.Full):
                q.put_nowait({"notice": message_to_dict(n), "timestamp": time.monotonic()})

        if not notices_only:
            self.sup.on_telemetry(on_b)
        self.sup.on_notice(on_n)
        try:
            while not self._stop.is_set():
                why = self.sup.link_problem()
                if why is not None:
                    err = self.sup._link_lost_error(why)
                    send({"error": {"type": type(err).__name__, "message": str(err)}})
                    return
                try:
                    item = q.get(timeout=0.2)
                except queue.Empty:
                    continue
                send(item)
        except OSError:
            pass
        finally:
            with contextlib.suppress(ValueError):
                self.sup.remove_telemetry_callback(on_b)
            with contextlib.suppress(ValueError):
                self.sup.remove_notice_callback(on_n)


# ---------------------------------------------------------------- client


class SessionClient:
    """A connection to a running session; request() and notices() behave as the
    Supervisor's do for the CLI."""

    def __init__(self, path: Path, sock: socket.socket, *, read_timeout_s: float = 30.0) -> None:
        self.path = path
        self._sock = sock
        self._rf = sock.makefile("r", encoding="utf-8")
        self._read_timeout_s = read_timeout_s
        self._open_stream = False
        self.connected = True

    @classmethod
    def attach(cls, path: Path, *, on_stale: Callable[[str], None] | None = None) -> SessionClient | None:
        """A client of the session at `path`, or None when none runs. A socket file no
        process listens on is removed (on_stale gets a message saying so)."""
        if not path.exists():
            return None
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            sock.connect(str(path))
        except OSError as exc:
            sock.close()
            if exc.errno in (errno.ECONNREFUSED, errno.ENOTSOCK, errno.ENOENT):
                with contextlib.suppress(FileNotFoundError):
                    path.unlink()
                if on_stale is not None and exc.errno != errno.ENOENT:
                    on_stale(f"removed stale session socket {path} (no process listens on it)")
                return None
            raise SessionError(f"cannot reach the session at {path}: {exc.strerror}; remove the file if "
                               f"no `landscape session` process runs") from None
        return cls(path, sock)

    def close(self) -> None:
        # Shut the socket down first: a thread blocked reading it (a quiet watch) holds the
        # reader's lock, which closing the reader would wait for.
        with contextlib.suppress(OSError):
            self._sock.shutdown(socket.SHUT_RDWR)
        with contextlib.suppress(OSError):
            self._rf.close()
        with contextlib.suppress(OSError):
            self._sock.close()

    def __enter__(self) -> SessionClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _gone(self, detail: str) -> SessionGoneError:
        return SessionGoneError(
            f"the background session at {self.path} ended ({detail}), and its lock and units with it: it "
            f"stops when its device stops answering or `landscape session stop` ends it; its log "
            f"{self.path.with_suffix('.log')} says which; start it again "
            f"(`landscape session start`)")

    def _send(self, obj: dict[str, Any]) -> None:
        self._drain()
        try:
            self._sock.sendall((json.dumps(obj) + "\n").encode())
        except OSError as exc:
            raise self._gone(exc.strerror or str(exc)) from None

    def _read(self, timeout_s: float | None = None) -> dict[str, Any]:
        self._sock.settimeout(timeout_s if timeout_s is not None else self._read_timeout_s)
        try:
            line = self._rf.readline()
        except TimeoutError:
            raise SessionError(f"the session at {self.path} did not answer within "
                               f"{timeout_s or self._read_timeout_s:g} s") from None
        except OSError as exc:
            raise self._gone(str(exc)) from None
        if not line:
            raise self._gone("it closed the connection")
        obj = json.loads(line)
        if "error" in obj:
            self._open_stream = False
            raise error_from_dict(obj["error"])
        return dict(obj)

    def _drain(self) -> None:
        while self._open_stream:
            if self._read().get("done"):
                self._open_stream = False

    def _call(self, obj: dict[str, Any], key: str) -> Any:
        self._send(obj)
        return self._read()[key]

    def status(self) -> dict[str, Any]:
        return dict(self._call({"op": "status"}, "status"))

    def telemetry(self) -> dict[str, dict[str, Any]]:
        return dict(self._call({"op": "telemetry"}, "telemetry"))

    def stop(self) -> None:
        self._call({"op": "stop"}, "stopping")

    def request(self, command: str | Command, /, *, check: bool = True, timeout_s: float | None = None,
                wait_s: float | None = None, **fields: Any) -> RetVal:
        """Run `command` in the session. With wait_s, notices() then yields its notices
        until the final one (or wait_s has passed). `check`: a negative code raises its
        CommandError subclass, as Supervisor.request does (check=False returns it)."""
        cmd = command if isinstance(command, Command) else lookup(command)
        self._send({"op": "request", "command": cmd.field, "fields": _jsonable(fields), "timeout_s": timeout_s,
                    "wait_s": wait_s})
        answer = self._read(self._read_timeout_s + 3 * (timeout_s or cmd.host_timeout_ms / 1000))
        rv = retval_from_dict(answer["retval"])
        self._open_stream = True
        if not (rv.started and wait_s is not None):
            self._drain()
        if check and rv.ret_code < 0:
            raise errors.error_for_code(cmd.name, rv.ret_code, rv.ret_msg)
        return rv

    def notices(self, timeout_s: float | None = None) -> Iterator[pb.Notice]:
        """The notices the session streams for the last request, until its end."""
        while self._open_stream:
            obj = self._read((timeout_s or 0) + self._read_timeout_s)
            if obj.get("done"):
                self._open_stream = False
                return
            if "notice" in obj:
                yield json_format.ParseDict(obj["notice"], pb.Notice())

    @property
    def connect_result_retval(self) -> RetVal:
        return self.request("connect", check=False)

    def disconnect(self, check: bool = True) -> RetVal:
        return self.request("disconnect", check=check)

    def watch(self, *, notices_only: bool = False) -> Iterator[tuple[str, Any, float]]:
        """Yield ("broadcast", tm.Broadcast, t) and ("notice", ls.Notice, t) from the session
        until the connection closes (use a client of its own); notices_only: no broadcasts."""
        self._send({"op": "watch", "notices_only": notices_only})
        self._sock.settimeout(None)
        for line in self._rf:
            obj = json.loads(line)
            if "error" in obj:
                raise error_from_dict(obj["error"])
            if "broadcast" in obj:
                b = obj["broadcast"]
                yield "broadcast", tm.Broadcast(b["name"], b["sender"], b["signals"], b["timestamp"]), b["timestamp"]
            elif "notice" in obj:
                yield "notice", json_format.ParseDict(obj["notice"], pb.Notice()), obj.get("timestamp", 0.0)
        raise SessionError(f"the session at {self.path} closed the connection: check `landscape session status`")
