"""landscape.model without a firmware build: the shipped model files read as landscaped reads them,
refusals name the file, line and key, and the packaged URDF of the default arm converts back into
its model (FK equal). tests/integration/test_model_file.py holds the refusals against landscaped's."""
from __future__ import annotations

import math
import random
from pathlib import Path

import numpy as np
import pytest

from landscape.model import ModelError, classify, from_urdf, load_model, parse_model
from landscape.urdf import urdf_text

ROOT = Path(__file__).resolve().parents[2]
ROBOTS = ROOT / "firmware" / "model" / "robots"


@pytest.mark.parametrize(("file", "cls"), [("ls-sim6.ini", "spherical_wrist"), ("kr6-r900.ini", "spherical_wrist"),
                                           ("puma560.ini", "spherical_wrist"), ("ur5e.ini", "offset_wrist"),
                                           ("ur10e.ini", "offset_wrist")])
def test_the_shipped_arms_load_with_their_ik_class(file: str, cls: str) -> None:
    m = load_model(ROBOTS / file)
    assert m.ik_class == cls and m.name == file.removesuffix(".ini")


def test_units_are_converted_to_si() -> None:
    m = load_model(ROBOTS / "ur5e.ini")
    assert m.joints[0]["max_velocity"] == 180 * (math.pi / 180.0)
    assert m.joints[0]["alpha"] == math.pi / 2 and m.joints[1]["a"] == -0.425
    k = load_model(ROBOTS / "kr6-r900.ini")
    assert k.joints[0]["d"] == 0.4  # 400 mm, divided: exactly 0.4


def test_a_refusal_names_the_file_line_and_key() -> None:
    text = (ROBOTS / "ls-sim6.ini").read_bytes()
    with pytest.raises(ModelError) as e:
        parse_model(text.replace(b"max = 150 deg", b"max = 150"), "arm.ini")
    assert str(e.value) == ("arm.ini:49: [joint.3] max: got '150', expected an angle: a number and its unit (deg or "
                            "rad), -540..540 deg")
    with pytest.raises(ModelError, match=r"^arm\.ini: \[cartesian\] max_linear_jerk: missing; every key"):
        parse_model(text.replace(b"max_linear_jerk = 40 m/s^3\n", b""), "arm.ini")
    with pytest.raises(ModelError, match="cannot read the robot model file: No such file or directory"):
        load_model("/nonexistent/arm.ini")


def test_classify_says_what_each_class_lacks() -> None:
    dh = load_model(ROBOTS / "ur5e.ini").dh()
    limits = [(-1.0, 1.0)] * 6
    assert classify(dh, limits) == "offset_wrist"
    dh[2] = (dh[2][0], 0.3, dh[2][2], dh[2][3])
    with pytest.raises(ModelError, match=r"alpha3 = 17\.1887 deg; alpha2 and alpha3 must be 0"):
        classify(dh, limits)


def test_the_packaged_urdf_converts_back_into_the_default_arm() -> None:
    text, m, chosen = from_urdf(urdf_text(), "ls-sim6.urdf")
    ref = load_model(ROBOTS / "ls-sim6.ini")
    assert m.name == "ls-sim6" and m.ik_class == "spherical_wrist" and "max_acceleration" in chosen
    rng = random.Random(1)
    for _ in range(200):
        q = [rng.uniform(j["min"], j["max"]) for j in ref.joints]
        assert float(np.abs(m.fk(q) - ref.fk(q)).max()) < 1e-12
    assert [j["min"] for j in m.joints] == [j["min"] for j in ref.joints]
