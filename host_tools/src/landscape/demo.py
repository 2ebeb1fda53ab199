"""The `landscape demo` sequence: lock, activate, joint moves, a tagged Cartesian path, release.

The sequence is data (``demo_steps``); ``run_demo`` runs it through a `call`
function the caller supplies (the CLI passes one that goes through its own
session or a background session and prints notices as they arrive). A command
the firmware answers CMD_NOT_IMPLEMENTED_ERR is reported as skipped and the demo
goes on; steps that need a skipped one are skipped too. The first other failure
ends the sequence, after a best-effort deactivate and release.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from ._generated import landscape_pb2 as pb
from .paths import PathFile, build_path_load_requests, parse_path_text, request_fields, resolve_settings
from .retval import RetVal

#: call(command, fields, wait) -> (RetVal, final notice or None when not waited / no final came)
Call = Callable[[str, dict[str, Any], bool], tuple[RetVal, "pb.Notice | None"]]

SKIPPED_NOT_IMPLEMENTED = "skipped: not implemented in this firmware"
READY_RAD = [0.0, -0.3, 0.6, 0.0, 0.9, 0.0]   # away from the wrist singularity (j5 != 0)
SIDE_RAD = [0.35, -0.15, 0.45, 0.2, 0.7, -0.3]


@dataclass
class Step:
    key: str
    title: str
    command: str
    fields: dict[str, Any] = field(default_factory=dict)
    wait: bool = False
    needs: tuple[str, ...] = ()      # keys of steps that must have run (not skipped)
    tolerate_errors: bool = False    # a refusal is reported, the demo goes on (clearing a path that may not exist)


@dataclass
class StepResult:
    step: Step
    status: str                      # "ok", "skipped", "tolerated", "failed"
    detail: str = ""
    retval: RetVal | None = None


@dataclass
class DemoResult:
    results: list[StepResult] = field(default_factory=list)

    @property
    def failed(self) -> list[StepResult]:
        return [r for r in self.results if r.status == "failed"]

    @property
    def ok(self) -> bool:
        return not self.failed


def demo_path() -> PathFile:
    """The demo's Cartesian path (package data landscape/data/demo_path.yaml)."""
    text = resources.files("landscape").joinpath("data/demo_path.yaml").read_text()
    return parse_path_text(text, "yaml", "demo_path.yaml")


def demo_steps(path: PathFile | None = None) -> list[Step]:
    pf = path or demo_path()
    s = resolve_settings(pf)
    loads = build_path_load_requests(s.path_name, pf.points, frame=s.frame, motion_type=s.motion_type,
                                     offset_type=s.offset_type)
    steps = [
        Step("lock", "take control", "lock"),
        Step("activate", "enable the drives", "activate", needs=("lock",)),
        Step("speed", "set the speed to 25 %", "set_speed", {"speed": 25.0, "attribute": pb.PERCENT_SPEED},
             needs=("activate",)),
        Step("ready", "joint move to the ready pose", "move_absolute",
             {"point_name": "demo_ready", "values": READY_RAD, "frame": pb.JOINT_FRAME, "speed_pct": 30.0},
             wait=True, needs=("activate",)),
        Step("side", "joint move to one side", "move_absolute",
             {"point_name": "demo_side", "values": SIDE_RAD, "frame": pb.JOINT_FRAME, "speed_pct": 30.0},
             wait=True, needs=("activate",)),
        Step("back", "relative joint move back to the ready pose", "move_relative",
             {"point_name": "demo_back", "values": [r - q for r, q in zip(READY_RAD, SIDE_RAD, strict=True)],
              "frame": pb.JOINT_FRAME, "speed_pct": 30.0}, wait=True, needs=("activate",)),
        Step("where", "read the robot position", "get_robot_position"),
        Step("clear_old", f"clear any old path '{s.path_name}'", "path_clear_path", {"path_name": s.path_name},
             needs=("lock",), tolerate_errors=True),
    ]
    for i, req in enumerate(loads):
        steps.append(Step("load" if i == 0 else f"load{i}",
                          f"load path '{s.path_name}' ({len(req.path_load.tags)} tagged points)", "path_load",
                          request_fields(req), needs=("lock",) + (("load",) if i else ())))
    steps += [
        Step("run", f"run path '{s.path_name}' once", "path_move", {"path_name": s.path_name, "number_of_cycles": 1},
             wait=True, needs=("activate", "load")),
        Step("clear", f"clear path '{s.path_name}'", "path_clear_path", {"path_name": s.path_name},
             needs=("load",)),
        Step("deactivate", "disable the drives", "deactivate", needs=("activate",)),
        Step("release", "give up control", "release", needs=("lock",)),
    ]
    return steps


def _run_step(step: Step, call: Call) -> StepResult:
    rv, final = call(step.command, step.fields, step.wait)
    if rv.ret_code == pb.CMD_NOT_IMPLEMENTED_ERR:
        return StepResult(step, "skipped", SKIPPED_NOT_IMPLEMENTED, rv)
    if rv.ret_code < 0:
        status = "tolerated" if step.tolerate_errors else "failed"
        return StepResult(step, status, f"{rv.ret_name}" + (f": {rv.ret_msg}" if rv.ret_msg else ""), rv)
    if step.wait and rv.started:
        if final is None:
            return StepResult(step, "failed", "no final notice (time-out): check get-motion-control-state", rv)
        if final.kind in (pb.ALARM, pb.ALARM_RSVP):
            return StepResult(step, "failed", f"alarm {final.event_id} " + " ".join(final.data), rv)
    return StepResult(step, "ok", "", rv)


def run_demo(call: Call, report: Callable[[StepResult], None], *, steps: list[Step] | None = None) -> DemoResult:
    """Run the demo's steps in order through `call`; `report` gets each result as it ends."""
    out = DemoResult()
    ran: set[str] = set()
    todo = steps if steps is not None else demo_steps()
    failed = False
    for step in todo:
        if failed and step.key not in ("deactivate", "release"):
            continue
        missing = [k for k in step.needs if k not in ran]
        if missing:
            res = StepResult(step, "skipped", f"skipped: needs '{missing[0]}', which did not run")
        else:
            res = _run_step(step, call)
            if res.status in ("ok", "tolerated"):
                ran.add(step.key)
            if res.status == "failed" and not failed:
                failed = True
        out.results.append(res)
        report(res)
    return out


def load_steps_from(path: Path) -> list[Step]:
    """The demo's steps with the Cartesian path taken from another path file."""
    from .paths import load_path_file

    return demo_steps(load_path_file(path))
