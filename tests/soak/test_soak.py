"""The soak's short mode (60 s) as a test: tests/soak/soak.py --short."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
BUILD = Path(os.environ.get("LS_BUILD_DIR", HERE.parents[1] / "build"))


def test_soak_short() -> None:
    exe = BUILD / "bin" / "landscaped"
    assert exe.exists(), f"{exe} is missing: build first"
    r = subprocess.run([sys.executable, str(HERE / "soak.py"), "--short"], capture_output=True, text=True,
                       timeout=240)
    print(r.stdout)
    assert r.returncode == 0, r.stdout + r.stderr
