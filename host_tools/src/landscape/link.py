"""Sharing one SLCAN link between local programs, as programs share a SocketCAN bus.

A pty (or a USB SLCAN adapter) has one reader: two programs that open it split its
bytes between them and both lose frames. So one process owns it: `LinkBroker`
(started by `landscape session start`) opens the serial line, opens the CAN
channel once, and serves the same SLCAN text on a TCP port of 127.0.0.1. Every
other program opens python-can's own slcan interface on that port
(``--interface slcan --channel socket://127.0.0.1:PORT``, pyserial's socket URL),
so no new wire format exists: a frame line a client writes goes to the device and
to every other client; a frame line from the device goes to every client. The
clients' channel commands (``O``, ``C``, ``S8``, ...) are answered but never
forwarded: one client closing its bus must not close the channel for the others.

The broker records itself in a small JSON file named after the serial line
(`holder_path`): `bus.open_bus` reads it and uses the broker's URL instead of the
pty, so every `landscape` command shares the link without options. The broker
also holds an exclusive flock on the line (pyserial's ``exclusive=True``), and a
`landscape` one-shot takes one too (`claim`): a second opener that finds the line
locked gets one line naming the holder (`LinkBusyError`), never a stolen byte.
"""
from __future__ import annotations

import contextlib
import errno
import fcntl
import hashlib
import json
import logging
import os
import queue
import socket
import tempfile
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import serial

from .errors import BusError

log = logging.getLogger("landscape.link")

#: SLCAN line kinds that carry a frame (11/29-bit data, remote, FD); everything else is a channel command.
FRAME_KINDS = frozenset("tTrRdDbB")
#: Frames a slow client may have queued before the broker drops its oldest (an rx overflow).
CLIENT_QUEUE_FRAMES = 4096
#: SLCAN bit-rate commands (python-can's table, the Lawicel codes).
SLCAN_BITRATES = {10000: "S0", 20000: "S1", 50000: "S2", 100000: "S3", 125000: "S4", 250000: "S5",
                  500000: "S6", 750000: "S7", 1000000: "S8", 83300: "S9"}
LOOPBACK = "127.0.0.1"


def line_end(buf: bytes | bytearray) -> int:
    """Index of the first SLCAN line terminator (CR, or BEL for an error) in `buf`, else -1."""
    cr, bel = buf.find(b"\r"), buf.find(b"\a")
    return cr if bel < 0 else bel if cr < 0 else min(cr, bel)


class LinkBusyError(BusError):
    """The serial line is already held by another process."""


def is_local_line(channel: str | None) -> bool:
    """Whether `channel` names a serial line on this machine (not a pyserial URL)."""
    return bool(channel) and "://" not in str(channel)


def _line_key(channel: str) -> str:
    return os.path.realpath(channel.split("@")[0])


def holder_path(channel: str) -> Path:
    """Where the broker of serial line `channel` describes itself:
    $XDG_RUNTIME_DIR/landscape-link-<hash of the line's real path>.json (else the temp directory)."""
    digest = hashlib.sha256(f"{_line_key(channel)}:{os.getuid()}".encode()).hexdigest()[:12]
    base = os.environ.get("XDG_RUNTIME_DIR") or tempfile.gettempdir()
    return Path(base) / f"landscape-link-{digest}.json"


@dataclass(frozen=True)
class Holder:
    """The process serving a serial line, as its holder file says."""

    pid: int
    channel: str
    url: str


def pid_alive(pid: int) -> bool:
    """Whether a process `pid` exists (another user's counts)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def read_holder(channel: str) -> Holder | None:
    """The live broker of `channel`, or None. A holder file whose process is gone is removed."""
    path = holder_path(channel)
    try:
        obj = json.loads(path.read_text(encoding="utf-8"))
        holder = Holder(int(obj["pid"]), str(obj["channel"]), str(obj["url"]))
    except FileNotFoundError:
        return None
    except (OSError, ValueError, KeyError, TypeError):
        log.warning("ignoring unreadable link holder file %s", path)
        return None
    if not pid_alive(holder.pid):
        with contextlib.suppress(FileNotFoundError):
            path.unlink()
        return None
    return holder


def lock_holder_pid(channel: str) -> int | None:
    """The pid holding a flock on `channel`'s inode, from /proc/locks (None when unknown)."""
    try:
        st = os.stat(_line_key(channel))
        text = Path("/proc/locks").read_text(encoding="ascii", errors="replace")
    except OSError:
        return None
    want = f":{st.st_ino}"
    for line in text.splitlines():
        parts = line.split()
        if len(parts) >= 6 and parts[1] == "FLOCK" and parts[5].endswith(want):
            with contextlib.suppress(ValueError):
                return int(parts[4])
    return None


def _describe_pid(pid: int | None) -> str:
    if pid is None:
        return "another process"
    try:
        argv = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
        cmd = " ".join(" ".join(a.decode(errors="replace").split()) for a in argv if a)
    except OSError:
        cmd = ""
    if len(cmd) > 80:
        cmd = cmd[:77] + "..."
    return f"pid {pid}" + (f" ({cmd})" if cmd else "")


def busy_message(channel: str, pid: int | None) -> str:
    """The one line a second opener of a held serial line gets (pure, for tests and docs)."""
    return (f"{channel} is already open in {_describe_pid(pid)}; a pty or SLCAN adapter has one reader: "
            f"run `landscape session start` once and every landscape command shares the link, "
            f"or end that process first")


_claims: dict[str, int] = {}
_claims_lock = threading.Lock()


def claim(channel: str) -> None:
    """Take an exclusive flock on serial line `channel` for the rest of this process (a second
    call for the same line is a no-op). Raises LinkBusyError naming the holder."""
    key = _line_key(channel)
    with _claims_lock:
        if key in _claims:
            return
        try:
            fd = os.open(key, os.O_RDONLY | os.O_NOCTTY | os.O_NONBLOCK | os.O_CLOEXEC)
        except OSError:
            return  # opening the bus reports a missing or unreadable line with its own hint
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            os.close(fd)
            if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN):
                raise LinkBusyError(busy_message(channel, lock_holder_pid(channel))) from None
            return
        _claims[key] = fd


def release(channel: str) -> None:
    """Drop this process's claim on `channel` (no-op without one)."""
    with _claims_lock:
        fd = _claims.pop(_line_key(channel), None)
    if fd is not None:
        os.close(fd)


# ---------------------------------------------------------------- the broker


class _Client:
    def __init__(self, conn: socket.socket, name: str) -> None:
        self.conn = conn
        self.name = name
        self.out: queue.Queue[bytes | None] = queue.Queue(maxsize=CLIENT_QUEUE_FRAMES)
        self.dropped = 0
        self.closed = threading.Event()

    def put(self, data: bytes) -> None:
        if self.closed.is_set():
            return
        try:
            self.out.put_nowait(data)
        except queue.Full:
            self.dropped += 1
            with contextlib.suppress(queue.Empty):
                self.out.get_nowait()
            with contextlib.suppress(queue.Full):
                self.out.put_nowait(data)

    def close(self) -> None:
        if not self.closed.is_set():
            self.closed.set()
            with contextlib.suppress(queue.Full):
                self.out.put_nowait(None)
            with contextlib.suppress(OSError):
                self.conn.shutdown(socket.SHUT_RDWR)


class LinkBroker:
    """Owns serial line `channel` and serves it as SLCAN on 127.0.0.1:`port` (0: any free one).

    start() opens the line exclusively, opens the CAN channel at `bitrate`, listens and
    writes the holder file; stop() undoes all of it. Threads: one reads the line, one
    accepts, two per client (reader, writer). Never blocks on a slow client: its queue
    drops the oldest frame (counted in `dropped`)."""

    def __init__(self, channel: str, *, bitrate: int = 1_000_000, port: int = 0) -> None:
        if bitrate not in SLCAN_BITRATES:
            raise BusError(f"SLCAN has no bit rate {bitrate}; use one of "
                           f"{', '.join(str(b) for b in sorted(SLCAN_BITRATES))}")
        self.channel = channel
        self.bitrate = bitrate
        self.port = port
        self.frames_from_device = 0
        self.frames_to_device = 0
        self._ser: serial.Serial | None = None
        self._sock: socket.socket | None = None
        self._clients: list[_Client] = []
        self._lock = threading.Lock()
        self._write_lock = threading.Lock()
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []

    @property
    def url(self) -> str:
        return f"socket://{LOOPBACK}:{self.port}"

    @property
    def dropped(self) -> int:
        with self._lock:
            return sum(c.dropped for c in self._clients)

    def start(self) -> str:
        """Open the line and serve it; returns the URL clients open. Raises LinkBusyError when
        another process holds the line, BusError when it cannot be opened."""
        holder = read_holder(self.channel)
        if holder is not None and holder.pid != os.getpid():
            raise LinkBusyError(f"{self.channel} is already served by pid {holder.pid} at {holder.url}: "
                                f"use that session (`landscape session status`)")
        try:
            self._ser = serial.Serial(self.channel, baudrate=115200, timeout=0.1, exclusive=True)
        except (serial.SerialException, OSError, ValueError) as exc:
            if isinstance(exc, serial.SerialException) and "exclusively lock" in str(exc):
                raise LinkBusyError(busy_message(self.channel, lock_holder_pid(self.channel))) from None
            raise BusError(f"cannot open serial line {self.channel}: {exc}; is landscaped running with "
                           f"--link slcan:pty:{self.channel}?") from None
        try:
            self._device_write(f"C\r{SLCAN_BITRATES[self.bitrate]}\rO\r".encode())
            sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.bind((LOOPBACK, self.port))
            sock.listen(16)
            sock.settimeout(0.2)
            self._sock = sock
            self.port = int(sock.getsockname()[1])
        except BaseException:
            self.stop()
            raise
        for fn, name in ((self._device_loop, "device"), (self._accept_loop, "accept")):
            t = threading.Thread(target=fn, name=f"landscape-link-{name}", daemon=True)
            t.start()
            self._threads.append(t)
        self._write_holder()
        log.info("serving %s at %s", self.channel, self.url)
        return self.url

    def stop(self) -> None:
        """Close the channel, every client and the line; remove the holder file. Idempotent."""
        self._stop.set()
        path = holder_path(self.channel)
        with contextlib.suppress(OSError, ValueError, KeyError):
            if int(json.loads(path.read_text(encoding="utf-8"))["pid"]) == os.getpid():
                path.unlink()
        if self._sock is not None:
            with contextlib.suppress(OSError):
                self._sock.close()
        with self._lock:
            clients, self._clients = self._clients, []
        for c in clients:
            c.close()
        for t in self._threads:
            if t is not threading.current_thread():
                t.join(2.0)
        self._threads.clear()
        if self._ser is not None:
            with contextlib.suppress(serial.SerialException, OSError):
                self._device_write(b"C\r")
            with contextlib.suppress(serial.SerialException, OSError):
                self._ser.close()
            self._ser = None

    def __enter__(self) -> LinkBroker:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _write_holder(self) -> None:
        path = holder_path(self.channel)
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        old = os.umask(0o177)
        try:
            tmp.write_text(json.dumps({"pid": os.getpid(), "channel": self.channel, "url": self.url}),
                           encoding="utf-8")
        finally:
            os.umask(old)
        os.replace(tmp, path)

    def _device_write(self, data: bytes) -> None:
        ser = self._ser
        if ser is None:
            return
        with self._write_lock:
            ser.write(data)

    def _fan_out(self, line: bytes, source: _Client | None) -> None:
        with self._lock:
            clients = list(self._clients)
        for c in clients:
            if c is not source:
                c.put(line)

    def _device_loop(self) -> None:
        buf = bytearray()
        while not self._stop.is_set():
            ser = self._ser
            if ser is None:
                return
            try:
                chunk = ser.read(max(1, ser.in_waiting))
            except (serial.SerialException, OSError, TypeError) as exc:
                if not self._stop.is_set():
                    log.error("the serial line %s failed: %s; clients see no more frames", self.channel, exc)
                return
            if not chunk:
                continue
            buf.extend(chunk)
            while True:
                cut = line_end(buf)
                if cut < 0:
                    break
                line = bytes(buf[:cut])
                del buf[:cut + 1]
                if line and chr(line[0]) in FRAME_KINDS:
                    self.frames_from_device += 1
                    self._fan_out(line + b"\r", None)

    def _accept_loop(self) -> None:
        sock = self._sock
        assert sock is not None
        n = 0
        while not self._stop.is_set():
            try:
                conn, addr = sock.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            conn.settimeout(None)
            n += 1
            client = _Client(conn, f"{addr[0]}:{addr[1]}")
            with self._lock:
                self._clients.append(client)
            for fn, name in ((self._client_reader, "rd"), (self._client_writer, "wr")):
                threading.Thread(target=fn, args=(client,), name=f"landscape-link-{name}{n}", daemon=True).start()

    def _client_writer(self, client: _Client) -> None:
        while True:
            data = client.out.get()
            if data is None:
                return
            try:
                client.conn.sendall(data)
            except OSError:
                self._drop(client)
                return

    def _client_reader(self, client: _Client) -> None:
        buf = bytearray()
        try:
            while not self._stop.is_set():
                chunk = client.conn.recv(4096)
                if not chunk:
                    break
                buf.extend(chunk)
                while True:
                    cut = buf.find(b"\r")
                    if cut < 0:
                        break
                    line = bytes(buf[:cut])
                    del buf[:cut + 1]
                    self._client_line(client, line)
        except OSError:
            pass
        finally:
            self._drop(client)

    def _client_line(self, client: _Client, line: bytes) -> None:
        if not line:
            return  # python-can's bare CR that clears an adapter's buffer
        if chr(line[0]) in FRAME_KINDS:
            try:
                self._device_write(line + b"\r")
            except (serial.SerialException, OSError) as exc:
                log.error("cannot write to %s: %s", self.channel, exc)
                client.put(b"\a")
                return
            self.frames_to_device += 1
            self._fan_out(line + b"\r", client)
            return
        # A channel command (O, C, L, Sn, sXXYY, V, N, Z, F, ...): the channel is the broker's,
        # so it is acknowledged and never forwarded.
        client.put(b"\r")

    def _drop(self, client: _Client) -> None:
        with self._lock:
            if client in self._clients:
                self._clients.remove(client)
        client.close()
        with contextlib.suppress(OSError):
            client.conn.close()

    def clients(self) -> int:
        with self._lock:
            return len(self._clients)


def status(holder: Holder | None) -> dict[str, Any]:
    """A holder as JSON-able fields (for `session status`)."""
    return {} if holder is None else {"link_pid": holder.pid, "link_channel": holder.channel, "link_url": holder.url}
