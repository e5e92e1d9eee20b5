"""Every script of benchmarks/ loads (and one with an argparse parser answers --help): the scripts
are run by hand and by `make bench`, not by the suite, and two had broken unseen (bench_train
importing a `solve` that had moved to dynamics.solvers; bench_recording logging on a timeline
that had been renamed). Loading imports the script's modules without measuring anything; the few
scripts that read sys.argv by hand (their first argument a number or a path) are loaded without
running their main."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from conftest import process_timeout

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
SCRIPTS = sorted(p for p in BENCHMARKS.glob("*.py") if not p.name.startswith("_"))


LOAD = ("import runpy, sys; sys.path.insert(0, {where!r}); "
        "runpy.run_path({script!r}, run_name='benchmark_loaded_by_the_tests')")


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.name)
def test_the_script_loads(script):
    parser = "argparse" in script.read_text()
    command = ([sys.executable, str(script), "--help"] if parser else
               [sys.executable, "-c", LOAD.format(where=str(BENCHMARKS), script=str(script))])
    proc = subprocess.run(command, capture_output=True, text=True, timeout=process_timeout(60.0),
                          cwd=BENCHMARKS.parent, start_new_session=True)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert not parser or "usage" in proc.stdout.lower()
