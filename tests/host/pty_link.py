"""The device end of an SLCAN pseudo-terminal, for tests that need the bus in another process.

python-can's `virtual` bus lives inside one process; a background session is a
process of its own. This bus reads the SLCAN lines a host (python-can `slcan`
on `path`) writes to the pty and writes received frames back as SLCAN lines, so
the fake device in the test process and the session process share one link,
as landscaped's `--link slcan:pty:PATH` does.
"""
from __future__ import annotations

import os
import queue
import select
import threading
import tty
from typing import Any

import can


class PtySlcanBus(can.BusABC):
    def __init__(self, **kwargs: Any) -> None:
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)  # no echo, no line editing: the bytes pass as they are
        self.path = os.ttyname(self._slave)
        self._rx: queue.Queue[can.Message] = queue.Queue()
        self._wlock = threading.Lock()
        self._stop = threading.Event()
        self._buf = b""
        self._thread = threading.Thread(target=self._reader, daemon=True, name="pty-slcan")
        self._thread.start()
        super().__init__(channel=self.path, **kwargs)
        self.channel_info = f"pty-slcan:{self.path}"

    def _reader(self) -> None:
        while not self._stop.is_set():
            ready, _, _ = select.select([self._master], [], [], 0.05)
            if not ready:
                continue
            try:
                chunk = os.read(self._master, 4096)
            except OSError:
                continue  # EIO while no process has the slave open
            self._buf += chunk
            while b"\r" in self._buf:
                line, self._buf = self._buf.split(b"\r", 1)
                msg = self._parse(line.decode("ascii", "replace").lstrip("\a"))
                if msg is not None:
                    self._rx.put(msg)

    @staticmethod
    def _parse(line: str) -> can.Message | None:
        if not line or line[0] not in "tT":
            return None  # O, C, S8, V ...: the host configuring the adapter
        ext = line[0] == "T"
        n = 8 if ext else 3
        try:
            arb = int(line[1:1 + n], 16)
            dlc = int(line[1 + n], 16)
            data = bytes.fromhex(line[2 + n:2 + n + 2 * dlc])
        except (ValueError, IndexError):
            return None
        return can.Message(arbitration_id=arb, is_extended_id=ext, dlc=dlc, data=data)

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        try:
            return self._rx.get(timeout=timeout), False
        except queue.Empty:
            return None, False

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        data = bytes(msg.data[:msg.dlc])
        head = f"T{msg.arbitration_id:08X}" if msg.is_extended_id else f"t{msg.arbitration_id:03X}"
        line = f"{head}{len(data)}{data.hex().upper()}\r".encode()
        with self._wlock:
            os.write(self._master, line)

    def shutdown(self) -> None:
        self._stop.set()
        self._thread.join(1.0)
        for fd in (self._master, self._slave):
            try:
                os.close(fd)
            except OSError:
                pass
        super().shutdown()
