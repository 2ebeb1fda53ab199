"""Which writer or reader a recording file gets, from its suffix.

recording.py writes and reads CSV and JSON lines; mcap_log.py writes and reads
MCAP and builds on recording.py. This module sits above both, so neither
imports the other back.
"""
from __future__ import annotations

from pathlib import Path

from .mcap_log import McapRecorder, recording_from_mcap
from .recording import Recorder, Recording, read_text_recording, record_format


def open_recorder(path: str | Path, *, start_s: float | None = None) -> Recorder | McapRecorder:
    """The writer for `path`'s suffix: McapRecorder for .mcap, else Recorder (CSV, JSON lines)."""
    if record_format(path) == "mcap":
        return McapRecorder(path, start_s=start_s)
    return Recorder(path, start_s=start_s)


def read_recording(path: str | Path) -> Recording:
    """Read a recording written by Recorder (CSV or JSON lines) or McapRecorder (MCAP)."""
    if record_format(path) == "mcap":
        return recording_from_mcap(Path(path))
    return read_text_recording(path)
