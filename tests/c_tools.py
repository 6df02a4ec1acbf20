"""The C tools the export's tests build with (gcc, make, cmake): installed by
scripts/c-tools-for-tests when missing (as .ci/run does), else the test fails saying which."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "c-tools-for-tests"
TOOLS = ("gcc", "make", "cmake")


def ensure_c_tools() -> None:
    if all(shutil.which(tool) for tool in TOOLS):
        return
    subprocess.run([str(SCRIPT)], check=False, timeout=900)
    missing = [tool for tool in TOOLS if shutil.which(tool) is None]
    assert not missing, f"the export's tests need {', '.join(missing)}: run scripts/c-tools-for-tests"
