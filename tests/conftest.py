import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "assets" / "scenes"


@pytest.fixture
def scenes_dir() -> Path:
    return SCENES


def run_cli(*args, cwd=None, timeout=120):
    """Run `python -m explorer ...` in a subprocess; returns CompletedProcess (text)."""
    env = dict(os.environ)
    env.setdefault("PYTHONWARNINGS", "ignore")
    return subprocess.run(
        [sys.executable, "-m", "explorer", *map(str, args)],
        capture_output=True, text=True, cwd=cwd or ROOT, timeout=timeout, env=env,
    )
