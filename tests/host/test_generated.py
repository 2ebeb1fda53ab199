"""The committed protocol artefacts of the host package equal a fresh generation from protocol/."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
GEN = ROOT / "host_tools" / "src" / "landscape" / "_generated"
FIX = "run host_tools/update_generated.sh and commit the result"


def test_pb2_matches_fresh_protoc_output(tmp_path: Path) -> None:
    protoc = shutil.which("protoc")
    # .ci/setup installs it, and the build itself needs it: its absence is a set-up bug.
    assert protoc is not None, "protoc is missing: install Debian's protobuf-compiler (bash .ci/setup)"
    subprocess.run([protoc, f"-I{ROOT / 'protocol'}", "-I/usr/include", f"--python_out={tmp_path}",
                    f"--pyi_out={tmp_path}", f"--descriptor_set_out={tmp_path / 'landscape.desc'}",
                    str(ROOT / "protocol" / "landscape.proto")], check=True)
    for name in ("landscape_pb2.py", "landscape_pb2.pyi", "landscape.desc"):
        fresh = (tmp_path / name).read_bytes()
        assert (GEN / name).read_bytes() == fresh, f"{name} is stale: {FIX}"


def test_dbc_copy_matches_protocol() -> None:
    assert (GEN / "landscape.dbc").read_bytes() == (ROOT / "protocol" / "landscape.dbc").read_bytes(), \
        f"landscape.dbc is stale: {FIX}"


def test_schema_hash_equals_gen_registry() -> None:
    """The host's hash is computed exactly as protocol/gen_registry.py computes the firmware's."""
    import importlib.util

    from landscape.registry import SCHEMA_HASH

    spec = importlib.util.spec_from_file_location("gen_registry", ROOT / "protocol" / "gen_registry.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    assert SCHEMA_HASH == mod.schema_hash((GEN / "landscape.desc").read_bytes())
    assert 0 < SCHEMA_HASH < 2**32


def test_urdf_copy_matches_the_robot_model() -> None:
    """The packaged URDF is what the built ls_urdf prints from firmware/model/ls_robot_model.c."""
    ls_urdf = Path(os.environ.get("LS_BUILD_DIR", ROOT / "build")) / "bin" / "ls_urdf"
    assert ls_urdf.exists(), f"{ls_urdf} is missing: build first (bash .ci/build)"
    fresh = subprocess.run([str(ls_urdf)], capture_output=True, check=True).stdout
    assert (GEN / "ls-sim6.urdf").read_bytes() == fresh, f"ls-sim6.urdf is stale: {FIX}"


def test_model_keys_copy_matches_the_firmwares_key_table() -> None:
    """The packaged robot-model keys are what the built ls_robot_model prints from
    firmware/model/ls_robot_model_file.c (`landscape model check` reads them)."""
    tool = Path(os.environ.get("LS_BUILD_DIR", ROOT / "build")) / "bin" / "ls_robot_model"
    assert tool.exists(), f"{tool} is missing: build first (bash .ci/build)"
    fresh = subprocess.run([str(tool), "keys"], capture_output=True, check=True).stdout
    assert (GEN / "robot-model-keys.json").read_bytes() == fresh, f"robot-model-keys.json is stale: {FIX}"


def test_options_copy_matches_protocol() -> None:
    assert (GEN / "landscape.options").read_bytes() == (ROOT / "protocol" / "landscape.options").read_bytes(), \
        f"landscape.options is stale: {FIX}"


def test_command_index_matches_the_schema_and_the_handlers(tmp_path: Path) -> None:
    """docs/handlers.md leads from every command's wire name to its handler and file."""
    out = tmp_path / "handlers.md"
    subprocess.run([sys.executable, str(ROOT / "protocol" / "gen_registry.py"), "--index", str(GEN),
                    str(ROOT / "firmware" / "core"), str(out)], check=True)
    assert (ROOT / "docs" / "handlers.md").read_text() == out.read_text(), f"docs/handlers.md is stale: {FIX}"
