"""Recording telemetry broadcasts and notices to CSV or JSON lines, and reading them back.

Every row carries `host_monotonic_s` (the host's monotonic clock when the frame
or notice arrived; one clock for every process of the machine) and `t_s`
(seconds since the recording started). `device_time_ms` is the device's own
clock where a broadcast carries one (TOOL_POS.tool_time_ms, 16 bits on the bus,
unwrapped here into a steadily increasing count), else empty.

CSV (`.csv`): one row per broadcast or notice, a fixed header: the time columns,
`kind` (broadcast or notice), `name` (DBC message or notice event_id), `sender`,
one column per signal of RECORDED_MESSAGES, named with its DBC unit (`j1_rad`,
`tool_x_m`; `column_name`), then `notice_kind`, `data` (';'-joined), `ref_seq`,
`final`. A row fills only its own columns. Broadcasts are SI, as the DBC defines them.
JSON lines (`.jsonl`, `.json`, `.ndjson`): one object per row with `signals` (keyed
by the same unit-named columns) or `notice` (the Notice as a dict).
MCAP (`.mcap`): channels with schemas for viewers such as Foxglove, written by
mcap_log.McapRecorder, which builds on this module. record_files picks the writer
or reader of all three from a file's suffix.
"""
from __future__ import annotations

import csv
import json
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

from . import telemetry as tm
from ._generated import landscape_pb2 as pb
from .errors import ArgumentError, LandscapeError
from .registry import message_to_dict

RECORDED_MESSAGES: tuple[str, ...] = ("JOINTS_12", "JOINTS_34", "JOINTS_56", "JOINTS_CMD_12", "JOINTS_CMD_34",
                                      "JOINTS_CMD_56", "TOOL_POS", "TOOL_RPY", "STATUS", "DIO")
TIME_COLUMNS: tuple[str, ...] = ("host_monotonic_s", "t_s", "device_time_ms")
NOTICE_COLUMNS: tuple[str, ...] = ("notice_kind", "data", "ref_seq", "final")
FORMATS: dict[str, str] = {".csv": "csv", ".jsonl": "jsonl", ".json": "jsonl", ".ndjson": "jsonl", ".mcap": "mcap"}


class RecordingError(LandscapeError):
    """A recording cannot be written or read."""


def column_name(signal: str) -> str:
    """The column of a DBC signal: its name with its DBC unit (`j1_rad`, `tool_x_m`), unless the
    name already ends with it (`tool_time_ms`) or it has none (`st_motion`)."""
    unit = _signal_units().get(signal, "")
    return f"{signal}_{unit}" if unit and not signal.endswith("_" + unit) else signal


def _signal_units() -> dict[str, str]:
    db = tm.database()
    return {s.name: (s.unit or "").replace("/", "_per_") for m in db.messages for s in m.signals}


def signal_columns() -> list[str]:
    """The column of every signal of RECORDED_MESSAGES, in DBC order."""
    db = tm.database()
    return [column_name(s.name) for name in RECORDED_MESSAGES for s in db.get_message_by_name(name).signals]


def _signal_of_column() -> dict[str, str]:
    db = tm.database()
    return {column_name(s.name): s.name for m in db.messages for s in m.signals}


def record_format(path: str | Path) -> str:
    fmt = FORMATS.get(Path(path).suffix.lower())
    if fmt is None:
        raise ArgumentError(f"{path}: unknown recording type '{Path(path).suffix}': use .mcap, .csv or .jsonl "
                            f"(also .json, .ndjson)")
    return fmt


class Recorder:
    """Writes broadcasts and notices as they come (thread-safe: telemetry and notices
    arrive in different threads). Use as a context manager."""

    def __init__(self, path: str | Path, *, start_s: float | None = None) -> None:
        self.path = Path(path)
        self.format = record_format(path)
        if self.format == "mcap":
            raise ArgumentError(f"{path}: Recorder writes CSV or JSON lines; record_files.open_recorder() opens .mcap")
        self.start_s = time.monotonic() if start_s is None else start_s
        self.broadcasts = 0
        self.notices = 0
        self._lock = threading.Lock()
        self._last_dev_ms: int | None = None
        self._dev_wraps = 0
        self._columns = list(TIME_COLUMNS) + ["kind", "name", "sender"] + signal_columns() + list(NOTICE_COLUMNS)
        try:
            self._f: IO[str] = self.path.open("w", newline="", encoding="utf-8")
        except OSError as exc:
            raise RecordingError(f"cannot write {path}: {exc.strerror or exc}") from None
        self._csv: Any = None
        if self.format == "csv":
            self._csv = csv.DictWriter(self._f, fieldnames=self._columns, extrasaction="ignore")
            self._csv.writeheader()

    def __enter__(self) -> Recorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        with self._lock:
            if not self._f.closed:
                self._f.close()

    def _device_ms(self, raw: Any) -> int:
        """Unwrap the 16-bit device clock (one wrap every 65.536 s)."""
        ms = int(raw) & 0xFFFF
        if self._last_dev_ms is not None and ms < self._last_dev_ms:
            self._dev_wraps += 1
        self._last_dev_ms = ms
        return ms + self._dev_wraps * 0x10000

    def broadcast(self, b: tm.Broadcast) -> None:
        """Record a decoded broadcast (others than RECORDED_MESSAGES are ignored)."""
        if b.name not in RECORDED_MESSAGES:
            return
        with self._lock:
            if self._f.closed:
                return
            dev = self._device_ms(b.signals["tool_time_ms"]) if "tool_time_ms" in b.signals else None
            row: dict[str, Any] = {"host_monotonic_s": round(b.timestamp, 6),
                                   "t_s": round(b.timestamp - self.start_s, 6),
                                   "device_time_ms": dev, "kind": "broadcast", "name": b.name, "sender": b.sender}
            signals = {column_name(k): _plain(v) for k, v in b.signals.items()}
            if self._csv is not None:
                row.update(signals)
                self._csv.writerow(row)
            else:
                row["signals"] = signals
                self._f.write(json.dumps(row) + "\n")
            self._f.flush()
            self.broadcasts += 1

    def notice(self, n: pb.Notice, timestamp: float | None = None) -> None:
        ts = time.monotonic() if timestamp is None else timestamp
        with self._lock:
            if self._f.closed:
                return
            row: dict[str, Any] = {"host_monotonic_s": round(ts, 6), "t_s": round(ts - self.start_s, 6),
                                   "device_time_ms": None, "kind": "notice", "name": n.event_id, "sender": None}
            if self._csv is not None:
                row.update({"notice_kind": pb.NoticeKind.Name(n.kind), "data": ";".join(n.data),
                            "ref_seq": n.ref_seq, "final": n.final})
                self._csv.writerow(row)
            else:
                row["notice"] = message_to_dict(n)
                self._f.write(json.dumps(row) + "\n")
            self._f.flush()
            self.notices += 1


def _plain(v: Any) -> Any:
    if isinstance(v, float):
        return round(v, 7)
    if isinstance(v, (int, str)):
        return v
    return float(v)


# ---------------------------------------------------------------- reading back


@dataclass
class Recording:
    """A recording read back: per broadcast name, (t_s, signals) samples in order; notices;
    for MCAP also the joint states as recorded (t_s, positions [rad], velocities [rad/s] or None)."""

    path: Path
    series: dict[str, list[tuple[float, dict[str, float]]]] = field(default_factory=dict)
    notices: list[tuple[float, str, dict[str, str]]] = field(default_factory=list)  # (t_s, event_id, data)
    joint_states: list[tuple[float, list[float], list[float | None]]] = field(default_factory=list)


def _data_dict(items: list[str]) -> dict[str, str]:
    out: dict[str, str] = {}
    for item in items:
        k, _, v = item.partition("=")
        out[k] = v
    return out


def read_text_recording(path: str | Path) -> Recording:
    """Read a recording written by Recorder (CSV or JSON lines)."""
    p = Path(path)
    fmt = record_format(p)
    if fmt == "mcap":
        raise ArgumentError(f"{path}: an MCAP file; use record_files.read_recording()")
    rec = Recording(p)
    signal_of = _signal_of_column()  # unit-named columns back to DBC signal names
    try:
        f = p.open(newline="", encoding="utf-8")
    except OSError as exc:
        raise RecordingError(f"cannot read {p}: {exc.strerror or exc}") from None
    with f:
        try:
            if fmt == "csv":
                reader = csv.DictReader(f)
                if reader.fieldnames is None or "kind" not in reader.fieldnames or "t_s" not in reader.fieldnames:
                    raise RecordingError(f"{p}: not a recording of `landscape record` (no t_s/kind columns)")
                for row in reader:
                    t = float(row["t_s"])
                    if row["kind"] == "broadcast":
                        sig = {signal_of.get(k, k): float(v) for k, v in row.items() if v not in ("", None)
                               and k not in TIME_COLUMNS + ("kind", "name", "sender") + NOTICE_COLUMNS}
                        rec.series.setdefault(row["name"], []).append((t, sig))
                    elif row["kind"] == "notice":
                        rec.notices.append((t, row["name"], _data_dict(row["data"].split(";") if row["data"] else [])))
            else:
                for line in f:
                    if not line.strip():
                        continue
                    obj = json.loads(line)
                    t = float(obj["t_s"])
                    if obj["kind"] == "broadcast":
                        rec.series.setdefault(obj["name"], []).append(
                            (t, {signal_of.get(k, k): float(v) for k, v in obj["signals"].items()}))
                    elif obj["kind"] == "notice":
                        rec.notices.append((t, obj["name"], _data_dict(list(obj["notice"].get("data", [])))))
        except (ValueError, KeyError, TypeError) as exc:
            raise RecordingError(f"{p}: not a recording of `landscape record` ({exc})") from None
    return rec
