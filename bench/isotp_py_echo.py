"""The reference echo peer of the ISO-TP pty benchmark: python can-isotp as
the device on an SLCAN pseudo-terminal, the same link type and addressing as
bench_isotp_pty_echo (normal fixed 29-bit, device 0x10, host 0xF1; BS 8,
STmin 0, padding 0xCC). The device end of SLCAN is a few lines here (python-can
only has the host end). Every complete message is sent back.

Usage: python bench/isotp_py_echo.py PATH   (runs until SIGTERM/SIGINT)
"""

from __future__ import annotations

import collections
import os
import select
import signal
import sys
import tty

import isotp

ISOTP_PARAMS = {"blocksize": 8, "stmin": 0, "tx_padding": 0xCC, "tx_data_min_length": 8}


class SlcanDevice:
    """The adapter end of SLCAN on a pty master: frames in, frames out."""

    def __init__(self, path: str) -> None:
        self.master, slave = os.openpty()
        tty.setraw(slave)
        self.slave_keep = slave  # keeps the master from reading EIO while no host is attached
        if os.path.islink(path):
            os.unlink(path)
        os.symlink(os.ttyname(slave), path)
        self.path = path
        self.open = False
        self.partial = b""
        self.rx: collections.deque[isotp.CanMessage] = collections.deque()

    def pump(self, timeout_s: float) -> None:
        ready, _, _ = select.select([self.master], [], [], timeout_s)
        if not ready:
            return
        data = self.partial + os.read(self.master, 4096)
        *lines, self.partial = data.split(b"\r")
        replies = b""
        for line in lines:
            kind = line[:1]
            if kind in (b"t", b"T"):
                n_id = 3 if kind == b"t" else 8
                can_id = int(line[1:1 + n_id], 16)
                dlc = int(line[1 + n_id:2 + n_id], 16)
                payload = bytes.fromhex(line[2 + n_id:2 + n_id + 2 * dlc].decode())
                self.rx.append(isotp.CanMessage(arbitration_id=can_id, data=payload, dlc=dlc,
                                                extended_id=kind == b"T"))
                continue
            if kind == b"O":
                self.open = True
            elif kind == b"C":
                self.open = False
            replies += b"\r"
        if replies:
            os.write(self.master, replies)

    def recv(self) -> isotp.CanMessage | None:
        return self.rx.popleft() if self.rx else None

    def send(self, msg: isotp.CanMessage) -> None:
        if not self.open:
            return
        head = f"T{msg.arbitration_id:08X}" if msg.is_extended_id else f"t{msg.arbitration_id:03X}"
        line = f"{head}{len(msg.data)}{bytes(msg.data).hex().upper()}\r".encode()
        view = memoryview(line)
        while view:
            try:
                view = view[os.write(self.master, view):]
            except BlockingIOError:
                select.select([], [self.master], [], 0.01)

    def close(self) -> None:
        if os.path.islink(self.path):
            os.unlink(self.path)
        os.close(self.master)
        os.close(self.slave_keep)


def main() -> int:
    if len(sys.argv) != 2:
        print("usage: isotp_py_echo.py PATH", file=sys.stderr)
        return 2
    dev = SlcanDevice(sys.argv[1])
    stopping = []
    signal.signal(signal.SIGTERM, lambda *_: stopping.append(1))
    signal.signal(signal.SIGINT, lambda *_: stopping.append(1))
    address = isotp.Address(isotp.AddressingMode.NormalFixed_29bits, source_address=0x10, target_address=0xF1)
    stack = isotp.TransportLayerLogic(rxfn=dev.recv, txfn=dev.send, address=address, params=dict(ISOTP_PARAMS))
    echoed = 0
    try:
        while not stopping:
            busy = stack.transmitting() or stack.rx_state != stack.RxState.IDLE
            dev.pump(0.0 if busy else 0.05)
            stack.process()
            while stack.available():
                data = stack.recv()
                if data is not None:
                    stack.send(bytes(data))
                    echoed += 1
                    stack.process()
    finally:
        dev.close()
        print(f"isotp_py_echo: {echoed} messages echoed", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
