"""What the report builder's tests share: the report modules on the path, and a real physbench run."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

PHYSBENCH = os.environ.get("PHYSBENCH_EXE")


def physbench_run(out: Path, *args: str) -> Path:
    """`physbench run ARGS --budget 0 --out OUT`, checked; the test is skipped without the executable."""
    if not PHYSBENCH:
        pytest.skip("PHYSBENCH_EXE is not set (CTest sets it)")
    subprocess.run([PHYSBENCH, "run", *args, "--budget", "0", "--out", str(out)], check=True, capture_output=True)
    return out
