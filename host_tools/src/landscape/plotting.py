"""Plots of a recording (CSV, JSON lines or MCAP; matplotlib, Agg: no display needed).

`plot_joints`: joint positions over time [rad, with degrees on the right axis], one labelled line
per joint, tag events as dotted vertical lines labelled above the axes (the legend sits below the
plot so it hides no tag). `plot_velocity`: joint velocities [rad/s]: as recorded in an MCAP
(positions differenced over the device clock), else differenced over the recording's time stamps.
`plot_following`: the following error, commanded (JOINTS_CMD_12/34/56, the control loop's set-point)
minus measured (JOINTS_12/34/56) positions of the same telemetry cycle [rad, degrees on the right axis].
`plot_path`: the tool position (TOOL_POS) in 3-D with equal scales on x, y and z, start, end and
tags marked.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from .notices import TAG_EVENT
from .recording import Recording, RecordingError

KINDS = ("joints", "velocity", "following", "path")
JOINT_MESSAGES = ("JOINTS_12", "JOINTS_34", "JOINTS_56")
COMMAND_MESSAGES = ("JOINTS_CMD_12", "JOINTS_CMD_34", "JOINTS_CMD_56")


def _figure(width_in: float, height_in: float) -> Any:
    from matplotlib.figure import Figure  # imported late: matplotlib takes ~0.3 s to import

    return Figure(figsize=(width_in, height_in), dpi=100)


def joint_samples(rec: Recording) -> list[tuple[float, list[float], list[float | None]]]:
    """(t_s, positions [rad], velocities [rad/s] or None) per complete set of six joints.

    MCAP recordings carry them; for CSV/JSON lines the sets are gathered from JOINTS_12/34/56 in time
    order (a set closes at JOINTS_56) and velocities are differences over the host time stamps."""
    if rec.joint_states:
        return rec.joint_states
    events = sorted((t, name, sig) for name in JOINT_MESSAGES for t, sig in rec.series.get(name, []))
    out: list[tuple[float, list[float], list[float | None]]] = []
    cur: dict[str, float] = {}
    for t, name, sig in events:
        cur.update({k: v for k, v in sig.items() if k in {f"j{i}" for i in range(1, 7)}})
        if name == "JOINTS_56" and len(cur) == 6:
            q = [cur[f"j{i}"] for i in range(1, 7)]
            vel: list[float | None] = [None] * 6
            if out and t > out[-1][0]:
                dt = t - out[-1][0]
                vel = [(a - b) / dt for a, b in zip(q, out[-1][1], strict=True)]
            out.append((t, q, vel))
            cur = {}
    return out


def command_samples(rec: Recording) -> list[tuple[float, list[float]]]:
    """(t_s, commanded positions [rad]) per complete set of JOINTS_CMD_12/34/56 (a set closes at JOINTS_CMD_56)."""
    events = sorted((t, name, sig) for name in COMMAND_MESSAGES for t, sig in rec.series.get(name, []))
    out: list[tuple[float, list[float]]] = []
    cur: dict[str, float] = {}
    for t, name, sig in events:
        cur.update({k: v for k, v in sig.items() if k in {f"j{i}_cmd" for i in range(1, 7)}})
        if name == "JOINTS_CMD_56" and len(cur) == 6:
            out.append((t, [cur[f"j{i}_cmd"] for i in range(1, 7)]))
            cur = {}
    return out


def following_samples(rec: Recording) -> list[tuple[float, list[float]]]:
    """(t_s, commanded minus measured [rad]) per telemetry cycle: each commanded set with the measured set of
    its cycle, the latest one at or before it (the device sends JOINTS_12/34/56, then JOINTS_CMD_12/34/56)."""
    measured = joint_samples(rec)
    out: list[tuple[float, list[float]]] = []
    i = 0
    for t, cmd in command_samples(rec):
        while i + 1 < len(measured) and measured[i + 1][0] <= t:
            i += 1
        if measured and measured[i][0] <= t:
            out.append((t, [c - m for c, m in zip(cmd, measured[i][1], strict=True)]))
    return out


def _tags(rec: Recording, ax: Any) -> None:
    for t, event, data in rec.notices:
        if event == TAG_EVENT:
            ax.axvline(t, color="grey", linestyle=":", linewidth=0.8)
            ax.annotate(data.get("tag") or data.get("tag_name", ""), (t, 1.01), xycoords=("data", "axes fraction"),
                        rotation=60, va="bottom", ha="left", fontsize=7, color="dimgrey", annotation_clip=False)


def _time_plot(rec: Recording, out: str | Path, title: str, ylabel: str,
               lines: list[tuple[str, list[float], list[float]]], degrees: bool) -> Path:
    fig = _figure(10, 6)
    ax = fig.add_subplot(1, 1, 1)
    for label, ts, vs in lines:
        ax.plot(ts, vs, label=label, linewidth=1.4)
    _tags(rec, ax)
    ax.set_xlabel("time since the recording started [s]")
    ax.set_ylabel(ylabel)
    if degrees:
        sec = ax.secondary_yaxis("right", functions=(_deg, _rad))
        sec.set_ylabel(ylabel.replace("[rad/s]", "[deg/s]").replace("[rad]", "[deg]"))
    ax.set_title(f"{title}: {rec.path.name}", pad=42)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncols=6, fontsize=8, frameon=False)
    fig.tight_layout()
    return _save(fig, out)


def _deg(v: Any) -> Any:
    return v * (180.0 / math.pi)


def _rad(v: Any) -> Any:
    return v * (math.pi / 180.0)


def plot_joints(rec: Recording, out: str | Path) -> Path:
    """Joint positions [rad] against time [s] since the recording started."""
    samples = joint_samples(rec)
    if not samples:
        raise RecordingError(f"{rec.path}: no joint telemetry (JOINTS_12/34/56) to plot: record while the "
                             f"controller broadcasts")
    ts = [s[0] for s in samples]
    lines = [(f"joint {j + 1}", ts, [s[1][j] for s in samples]) for j in range(6)]
    return _time_plot(rec, out, "joint positions", "joint position [rad]", lines, degrees=True)


def plot_velocity(rec: Recording, out: str | Path) -> Path:
    """Joint velocities [rad/s] against time [s]."""
    samples = [s for s in joint_samples(rec) if all(v is not None for v in s[2])]
    if not samples:
        raise RecordingError(f"{rec.path}: fewer than two joint samples: no velocity to plot (record longer)")
    ts = [s[0] for s in samples]
    lines = [(f"joint {j + 1}", ts, [float(s[2][j] or 0.0) for s in samples]) for j in range(6)]
    return _time_plot(rec, out, "joint velocities", "joint velocity [rad/s]", lines, degrees=True)


def plot_following(rec: Recording, out: str | Path) -> Path:
    """Following error (commanded minus measured joint positions) [rad] against time [s]."""
    samples = following_samples(rec)
    if not samples:
        why = ("no commanded positions (JOINTS_CMD_12/34/56): the recording comes from a controller that does not "
               "broadcast them; record again with this version's landscaped") if joint_samples(rec) else \
            "no joint telemetry (JOINTS_12/34/56) to plot: record while the controller broadcasts"
        raise RecordingError(f"{rec.path}: {why}")
    ts = [s[0] for s in samples]
    lines = [(f"joint {j + 1}", ts, [s[1][j] for s in samples]) for j in range(6)]
    return _time_plot(rec, out, "following error (commanded - measured)", "following error [rad]", lines,
                      degrees=True)


def plot_path(rec: Recording, out: str | Path) -> Path:
    """The tool position [m] in 3-D (equal scales), coloured from start to end, with tags marked."""
    samples = rec.series.get("TOOL_POS", [])
    pts = [(t, s["tool_x"], s["tool_y"], s["tool_z"]) for t, s in samples
           if {"tool_x", "tool_y", "tool_z"} <= s.keys()]
    if not pts:
        raise RecordingError(f"{rec.path}: no tool position telemetry (TOOL_POS) to plot: record while the "
                             f"controller broadcasts")
    fig = _figure(7.5, 7)
    ax = fig.add_subplot(1, 1, 1, projection="3d")
    xs, ys, zs = [p[1] for p in pts], [p[2] for p in pts], [p[3] for p in pts]
    ax.plot(xs, ys, zs, color="tab:blue", linewidth=1.4, label="tool path")
    ax.scatter([xs[0]], [ys[0]], [zs[0]], color="tab:green", s=40, label="start")
    ax.scatter([xs[-1]], [ys[-1]], [zs[-1]], color="tab:red", s=40, label="end")
    times = [p[0] for p in pts]
    for t, event, data in rec.notices:
        if event != TAG_EVENT:
            continue
        i = min(range(len(times)), key=lambda k: abs(times[k] - t))
        ax.scatter([xs[i]], [ys[i]], [zs[i]], color="black", s=18, marker="^")
        ax.text(xs[i], ys[i], zs[i], " " + (data.get("tag") or data.get("tag_name", "")), fontsize=7)
    # Equal aspect: one cube around the path, so a straight line looks straight and a circle round.
    half = max(max(xs) - min(xs), max(ys) - min(ys), max(zs) - min(zs), 0.01) / 2
    for setter, vals in ((ax.set_xlim, xs), (ax.set_ylim, ys), (ax.set_zlim, zs)):
        mid = (max(vals) + min(vals)) / 2
        setter(mid - half, mid + half)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.set_title(f"tool path (base frame): {rec.path.name}")
    ax.legend(loc="upper left", fontsize=8)
    return _save(fig, out)


def _save(fig: Any, out: str | Path) -> Path:
    p = Path(out)
    try:
        fig.savefig(p, format=p.suffix.lstrip(".").lower() or "png")
    except (OSError, ValueError) as exc:
        raise RecordingError(f"cannot write the plot {p}: {exc}") from None
    return p


def plot(rec: Recording, out: str | Path, kind: str = "joints") -> Path:
    if kind == "joints":
        return plot_joints(rec, out)
    if kind == "velocity":
        return plot_velocity(rec, out)
    if kind == "following":
        return plot_following(rec, out)
    if kind == "path":
        return plot_path(rec, out)
    raise RecordingError(f"unknown plot kind '{kind}': use {', '.join(KINDS)}")
