"""Benchmark 3: a small blocking command through the whole stack (host
library -> SLCAN pty -> landscaped -> back) against the floor of the same
link (a C peer echoing every frame), and against an ISO-TP exchange of
exactly the command's request and answer sizes (the firmware's ISO-TP on the
same kind of pty), measured alternately so both see the same load."""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import can
import isotp

from common import BIN, BUILD, BenchError, Row, Section, fmt_ratio, median, need, percentile, pty_peer
from landscape._generated import landscape_pb2 as pb
from landscape.bus import ISOTP_PARAMS

# The ids of one request frame and its echo: ISO-TP normal fixed addressing
# between the default host and device addresses (protocol/landscape.proto).
TO_DEVICE = pb.ISOTP_PHYSICAL_BASE | pb.DEFAULT_DEVICE_ADDRESS << 8 | pb.DEFAULT_HOST_ADDRESS
FROM_DEVICE = pb.ISOTP_PHYSICAL_BASE | pb.DEFAULT_HOST_ADDRESS << 8 | pb.DEFAULT_DEVICE_ADDRESS


def slcan_bus(link: Path) -> can.BusABC:
    return can.Bus(interface="slcan", channel=str(link), bitrate=1000000, sleep_after_open=0)


class AnswerSizes(can.Listener):
    """The length of every ISO-TP message the device sends (any target), from the PCI of its single or
    first frame."""

    def __init__(self) -> None:
        self.sizes: list[int] = []

    def on_message_received(self, msg: can.Message) -> None:
        if not msg.is_extended_id or not msg.data or (msg.arbitration_id & 0x1FFF00FF) != (
                pb.ISOTP_PHYSICAL_BASE | pb.DEFAULT_DEVICE_ADDRESS):
            return
        pci = msg.data[0] >> 4
        if pci == 0:
            self.sizes.append(msg.data[0] & 0x0F)
        elif pci == 1 and len(msg.data) >= 2:
            self.sizes.append((msg.data[0] & 0x0F) << 8 | msg.data[1])


def request_bytes(seq: int) -> int:
    """The size of the getMotionControlState uplink the host library sends with `seq`."""
    from landscape.supervisor import Supervisor
    req = Supervisor.build_request("get_motion_control_state", seq)
    return len(pb.Uplink(request=req).SerializeToString())


def paired_round_trips(cmd_link: Path, echo_link: Path, runs: int) -> tuple[list[float], list[float], int, int]:
    """getMotionControlState through landscaped on `cmd_link` and an exchange of the same sizes with the
    ISO-TP peer on `echo_link`, alternately (one of each per turn). Returns both lists of round trips (s)
    and the request and answer sizes (B)."""
    try:
        from landscape.supervisor import Supervisor
    except ImportError as exc:
        raise BenchError(f"the host package `landscape` is not importable ({exc}): run .ci/setup") from None
    cmd_bus = slcan_bus(cmd_link)
    notifier = can.Notifier(cmd_bus, [], timeout=0.05)
    sizes = AnswerSizes()
    notifier.add_listener(sizes)
    sup = Supervisor(cmd_bus, notifier=notifier, source_address=pb.DEFAULT_HOST_ADDRESS)
    echo_bus = slcan_bus(echo_link)
    echo_notifier = can.Notifier(echo_bus, [], timeout=0.05)
    address = isotp.Address(isotp.AddressingMode.NormalFixed_29bits, source_address=pb.DEFAULT_HOST_ADDRESS,
                            target_address=pb.DEFAULT_DEVICE_ADDRESS)
    stack = isotp.NotifierBasedCanStack(echo_bus, echo_notifier, address=address, params=dict(ISOTP_PARAMS))
    stack.start()
    try:
        with sup:
            for _ in range(5):
                sizes.sizes.clear()
                sup.get_motion_control_state()
            if len(set(sizes.sizes)) != 1:
                raise BenchError(f"getMotionControlState's answers had sizes {sizes.sizes}: expected one size "
                                 "(did a notice come in between?)")
            answer_len = sizes.sizes[0]
            request_len = request_bytes(10 + runs // 2)  # about the middle run's seq: its varint varies by 1 B at most
            payload = bytes((i * 7) & 0xFF for i in range(request_len))
            cmd, echo = [], []
            for k in range(runs + 5):
                t0 = time.perf_counter()
                sup.get_motion_control_state()
                t1 = time.perf_counter()
                stack.send(payload)
                got = stack.recv(block=True, timeout=2.0)
                t2 = time.perf_counter()
                if got is None or len(got) != answer_len:
                    raise BenchError(f"no {answer_len}-byte answer from bench_isotp_pty_echo on {echo_link} "
                                     f"(got {'nothing' if got is None else f'{len(got)} B'})")
                if k >= 5:
                    cmd.append(t1 - t0)
                    echo.append(t2 - t1)
            return cmd, echo, request_len, answer_len
    finally:
        stack.stop()
        echo_notifier.stop()
        echo_bus.shutdown()
        notifier.stop()
        cmd_bus.shutdown()


def command_round_trips(link: Path, runs: int) -> list[float]:
    try:
        from landscape.supervisor import Supervisor
    except ImportError as exc:
        raise BenchError(f"the host package `landscape` is not importable ({exc}): run .ci/setup") from None
    sup = Supervisor(slcan_bus(link), owns_bus=True)
    with sup:
        for _ in range(5):
            sup.get_motion_control_state()
        out = []
        for _ in range(runs):
            t0 = time.perf_counter()
            sup.get_motion_control_state()
            out.append(time.perf_counter() - t0)
        return out


def command_answer_bytes(link: Path) -> int:
    """The size of getMotionControlState's answer from landscaped on `link` (a few calls, one size)."""
    from landscape.supervisor import Supervisor
    bus = slcan_bus(link)
    notifier = can.Notifier(bus, [], timeout=0.05)
    sizes = AnswerSizes()
    notifier.add_listener(sizes)
    try:
        with Supervisor(bus, notifier=notifier, source_address=pb.DEFAULT_HOST_ADDRESS) as sup:
            seen = []
            for _ in range(5):
                sizes.sizes.clear()
                sup.get_motion_control_state()
                seen += sizes.sizes
    finally:
        notifier.stop()
        bus.shutdown()
    if len(seen) != 5 or len(set(seen)) != 1:
        raise BenchError(f"getMotionControlState's answer sizes {seen}: expected one answer of one size per call")
    return seen[0]


def frame_round_trips(link: Path, runs: int) -> list[float]:
    """Raw python-can: send one 8-byte frame, wait for its echo."""
    bus = slcan_bus(link)
    try:
        out = []
        for k in range(runs + 5):
            msg = can.Message(arbitration_id=TO_DEVICE, is_extended_id=True, data=bytes([1, k & 0xFF] + [0xCC] * 6))
            t0 = time.perf_counter()
            bus.send(msg)
            while True:
                got = bus.recv(timeout=2.0)
                if got is None:
                    raise BenchError(f"no echo of a frame from bench_frame_echo on {link} within 2 s")
                if got.arbitration_id == FROM_DEVICE and got.data[1] == (k & 0xFF):
                    break
            if k >= 5:
                out.append(time.perf_counter() - t0)
        return out
    finally:
        bus.shutdown()


def isotp_sf_round_trips(link: Path, runs: int) -> list[float]:
    """python can-isotp (as the host library uses it): one single frame out, its echo back."""
    bus = slcan_bus(link)
    notifier = can.Notifier(bus, [], timeout=0.05)
    address = isotp.Address(isotp.AddressingMode.NormalFixed_29bits, source_address=0xF1, target_address=0x10)
    stack = isotp.NotifierBasedCanStack(bus, notifier, address=address,
                                        params={"blocksize": 8, "stmin": 0, "tx_padding": 0xCC,
                                                "tx_data_min_length": 8})
    stack.start()
    try:
        out = []
        for k in range(runs + 5):
            data = bytes([k & 0xFF, 2, 3, 4, 5, 6])
            t0 = time.perf_counter()
            stack.send(data)
            got = stack.recv(block=True, timeout=2.0)
            if got != data:
                raise BenchError(f"no ISO-TP single-frame echo from bench_frame_echo on {link}")
            if k >= 5:
                out.append(time.perf_counter() - t0)
        return out
    finally:
        stack.stop()
        notifier.stop()
        bus.shutdown()


def fig(xs: list[float]) -> str:
    return f"median {median(xs) * 1e3:.3f} ms, p99 {percentile(xs, 99) * 1e3:.3f} ms"


def bench_command(quick: bool) -> Section:
    sec = Section(3, "Command round trip: getMotionControlState through the whole stack vs the link's floor and "
                     "an ISO-TP exchange of the same sizes")
    runs = 100 if quick else 500
    landscaped = need(BUILD / "bin" / "landscaped", "the firmware")
    echo = need(BIN / "bench_frame_echo", "the SLCAN frame echo")
    tp_echo = need(BIN / "bench_isotp_pty_echo", "the firmware ISO-TP echo peer")
    with tempfile.TemporaryDirectory(prefix="lsbench-") as tmp:
        link = Path(tmp) / "ls0"
        link2 = Path(tmp) / "echo0"
        with pty_peer([str(landscaped), "--hal", "sim", "--link", f"slcan:pty:{link}"], link):
            cmd = command_round_trips(link, runs)
            answer_len = command_answer_bytes(link)
            with pty_peer([str(tp_echo), str(link2), str(answer_len)], link2):
                paired_cmd, paired_echo, req_len, ans_len = paired_round_trips(link, link2, runs)
        with pty_peer([str(echo), str(link)], link):
            raw = frame_round_trips(link, runs)
            sf = isotp_sf_round_trips(link, runs)
    sec.rows.append(Row("3a. getMotionControlState round trip (Supervisor -> landscaped)", fig(cmd),
                        "raw frame echo, same pty (python-can send/recv, C echo peer)", fig(raw),
                        f"{fmt_ratio(median(cmd) / median(raw))} (median), "
                        f"{fmt_ratio(percentile(cmd, 99) / percentile(raw, 99))} (p99)", f"{runs} runs each"))
    sec.rows.append(Row("3b. same command", fig(cmd), "ISO-TP single-frame echo (python can-isotp host stack)",
                        fig(sf), f"{fmt_ratio(median(cmd) / median(sf))} (median), "
                        f"{fmt_ratio(percentile(cmd, 99) / percentile(sf, 99))} (p99)",
                        "the floor of any ISO-TP request/answer with the host's stack"))
    ratio_med = median(paired_cmd) / median(paired_echo)
    sec.rows.append(Row(f"3c. same command, paired ({req_len} B request, {ans_len} B answer)", fig(paired_cmd),
                        "ISO-TP exchange of the same sizes, firmware ls_isotp peer, same pty type, alternating",
                        fig(paired_echo), f"{fmt_ratio(ratio_med)} (median), "
                        f"{fmt_ratio(percentile(paired_cmd, 99) / percentile(paired_echo, 99))} (p99)",
                        f"goal <= 1.5 at the median; {runs} pairs"))
    sec.details.append(
        "3c runs landscaped and `bench/isotp_pty_echo.c` (the firmware's ISO-TP on `hal/sim/slcan_pty`, "
        "answering every message with the command's answer size) on two ptys at once and alternates one "
        "command and one exchange per turn, so both see the same machine load; the request is the command's "
        "own uplink size, sent with the host library's ISO-TP parameters. Both peers sleep until a frame or "
        "their next ISO-TP deadline: landscaped's comms thread has no fixed poll period (it wakes on a link's "
        "fd, on the eventfd the control loop and the stop signals write, or on the earliest protocol, "
        "heartbeat or telemetry deadline; docs/architecture.md \"Threads\"), so a request is served when its "
        "last frame arrives. The difference is what the device adds (dispatch, protobuf, its comms loop) and "
        "what `landscape.Supervisor` adds on the host.")
    sec.details.append(
        "The command goes through `landscape.Supervisor` (protobuf request, can-isotp, python-can slcan) to "
        "`build-bench/bin/landscaped --hal sim` and back (its answer is a multi-frame ISO-TP message). Floors "
        "on the same pty type, answered by `bench/frame_echo.c` (echoes every frame, swapping the two "
        "address bytes of the 29-bit id): (a) one raw CAN frame out and back through python-can; (b) one "
        "ISO-TP single frame out and back through the same can-isotp stack the host library uses.")
    sec.commands.append("build-bench/bin/landscaped --hal sim --link slcan:pty:/tmp/ls0 &")
    sec.commands.append("build-bench/bench/bench_frame_echo /tmp/ls0 &")
    sec.commands.append(f"build-bench/bench/bench_isotp_pty_echo /tmp/echo0 {ans_len} &   # 3c, beside landscaped")
    return sec
