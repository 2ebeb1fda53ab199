"""Plots of a recording (matplotlib, Agg: no display needed).

`plot_joints`: joint positions over time, one labelled line per joint, tag
events as dotted vertical lines. `plot_path`: the tool position (TOOL_POS) in
3-D with start, end and tag points marked.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

from .recording import Recording, RecordingError

KINDS = ("joints", "path")


def _figure(width_in: float, height_in: float) -> Any:
    from matplotlib.figure import Figure  # imported late: matplotlib takes ~0.3 s to import

    return Figure(figsize=(width_in, height_in), dpi=100)


def plot_joints(rec: Recording, out: str | Path) -> Path:
    """Joint positions [rad] against time [s] since the recording started."""
    series = {f"j{i}": [] for i in range(1, 7)}  # type: dict[str, list[tuple[float, float]]]
    for name in ("JOINTS_12", "JOINTS_34", "JOINTS_56"):
        for t, sig in rec.series.get(name, []):
            for k, v in sig.items():
                if k in series:
                    series[k].append((t, v))
    if not any(series.values()):
        raise RecordingError(f"{rec.path}: no joint telemetry (JOINTS_12/34/56) to plot: record while the "
                             f"controller broadcasts")
    fig = _figure(10, 5.5)
    ax = fig.add_subplot(1, 1, 1)
    for joint, samples in series.items():
        if samples:
            ax.plot([s[0] for s in samples], [s[1] for s in samples], label=joint, linewidth=1.4)
    for t, event, data in rec.notices:
        if event == "tag":
            ax.axvline(t, color="grey", linestyle=":", linewidth=0.8)
            ax.annotate(data.get("tag") or data.get("tag_name", ""), (t, 1.0), xycoords=("data", "axes fraction"),
                        rotation=90, va="top", ha="right", fontsize=7, color="grey")
    ax.set_xlabel("time since the recording started [s]")
    ax.set_ylabel("joint position [rad]")
    ax.set_title(f"joint positions: {rec.path.name}")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper right", ncols=6, fontsize=8)
    fig.tight_layout()
    return _save(fig, out)


def plot_path(rec: Recording, out: str | Path) -> Path:
    """The tool position [m] in 3-D, coloured from start to end, with tags marked."""
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
        if event != "tag":
            continue
        i = min(range(len(times)), key=lambda k: abs(times[k] - t))
        ax.scatter([xs[i]], [ys[i]], [zs[i]], color="black", s=18, marker="^")
        ax.text(xs[i], ys[i], zs[i], " " + (data.get("tag") or data.get("tag_name", "")), fontsize=7)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.set_title(f"tool path: {rec.path.name}")
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
    if kind == "path":
        return plot_path(rec, out)
    raise RecordingError(f"unknown plot kind '{kind}': use {' or '.join(KINDS)}")
