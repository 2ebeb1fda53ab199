"""landscape teach's file work (docs/host-tool.md "teach"): a taught pose is appended to a path
file in the file's kind, and what is written always loads back; a file it cannot take is
refused with one line and left as it was."""
from __future__ import annotations

from pathlib import Path

import pytest

from landscape._generated import landscape_pb2 as pb
from landscape.paths import PathFileError, load_path_file
from landscape.teach import append_taught

Q = [0.1, -0.3, 0.6, 1.6661e-10, 0.9, -0.0]
POSE = [0.3356, 0.0, 0.6335, 3.14159265, -0.3708, 0.0]


def test_a_new_csv_gets_a_header_and_joint_values_without_float_noise(tmp_path: Path) -> None:
    f = tmp_path / "t.csv"
    assert append_taught(f, "a", joints=Q, world_pose=POSE) == ("joint", 1)
    assert append_taught(f, "b", joints=[0.2] * 6, world_pose=POSE) == ("joint", 2)
    assert f.read_text().splitlines() == ["j1,j2,j3,j4,j5,j6,tag_name", "0.1,-0.3,0.6,0.0,0.9,0.0,a",
                                          "0.2,0.2,0.2,0.2,0.2,0.2,b"]
    pf = load_path_file(f)
    assert [p.tag_name for p in pf.points] == ["a", "b"] and list(pf.points[0].joints) == [0.1, -0.3, 0.6, 0, 0.9, 0]


def test_an_existing_csv_keeps_its_column_order(tmp_path: Path) -> None:
    f = tmp_path / "t.csv"
    f.write_text("tag_name,speed_pct,j6,j5,j4,j3,j2,j1\nfirst,50,1,1,1,1,1,1")  # no newline at its end
    append_taught(f, "b", joints=Q, world_pose=POSE)
    assert f.read_text().splitlines()[-1] == "b,,0.0,0.9,0.0,0.6,-0.3,0.1"
    assert len(load_path_file(f).points) == 2


@pytest.mark.parametrize("suffix", [".yaml", ".json"])
def test_a_cartesian_pose_goes_to_a_file_in_the_world_frame(tmp_path: Path, suffix: str) -> None:
    f = tmp_path / f"t{suffix}"
    assert append_taught(f, "a", joints=Q, world_pose=POSE, kind="cartesian") == ("cartesian", 1)
    assert append_taught(f, "b", joints=Q, world_pose=POSE) == ("cartesian", 2)  # the file's kind
    pf = load_path_file(f)
    assert pf.frame == pb.WORLD_CARTESIAN_FRAME and pf.kind == "cartesian"
    assert list(pf.points[1].pose) == [0.3356, 0.0, 0.6335, 3.141593, -0.3708, 0.0]


@pytest.mark.parametrize(("name", "text", "kind", "why"), [
    ("t.csv", "", "cartesian", "a taught pose is the tool tip in the world frame"),
    ("t.yaml", "points:\n- {x: 0, y: 0, z: 0, roll: 0, pitch: 0, yaw: 0}\n", None, "frame: WORLD_CARTESIAN_FRAME"),
    ("t.csv", "j1,j2,j3,j4,j5,j6,tag_name\n0,0,0,0,0,0,a\n", "cartesian", "holds joint points"),
    ("t.csv", "j1,j2,j3,j4,j5,j6\n0,0,0,0,0,0\n", None, "tag_name: no such column"),
    ("t.csv", "j1,j2,j3\n0,0,0\n", None, "its points have 3 joint values, the arm has 6"),
    ("t.csv", "j1,bogus\n", None, "unknown column"),
    ("t.txt", "", None, "unknown file type"),
])
def test_a_file_teach_cannot_take_is_refused_and_left_as_it_was(tmp_path: Path, name: str, text: str,
                                                                kind: str | None, why: str) -> None:
    f = tmp_path / name
    f.write_text(text)
    with pytest.raises(PathFileError) as exc:
        append_taught(f, "a", joints=Q, world_pose=POSE, kind=kind)
    assert why in str(exc.value) and str(f) in str(exc.value)
    assert f.read_text() == text


def test_a_name_longer_than_a_tag_is_refused(tmp_path: Path) -> None:
    f = tmp_path / "t.csv"
    with pytest.raises(PathFileError, match="tag_name"):
        append_taught(f, "n" * 64, joints=Q, world_pose=POSE)
    assert not f.exists()
