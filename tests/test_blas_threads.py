"""The command's figures do not depend on how many cores the machine has: `explorer` runs LAPACK
on one thread unless the user chose otherwise (explorer/cli/__init__.py). A threaded LAPACK sums
in another order: the tabulated law's spline (table_demo) moved by ~1e-9 relative between one and
two threads on the 2-core test machine, and the golden-scene check, run outside `make`, reported
it as a difference."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
from conftest import ROOT, kill_tree, process_timeout

CHILD = """
import sys
import explorer.cli  # first, as the `explorer` command does: before numpy or scipy load OpenBLAS
import numpy as np
from explorer import load_scene, simulate
result = simulate(load_scene(sys.argv[1]))
np.savez(sys.argv[2], **{k: np.asarray(v) for k, v in result.columns.items() if np.asarray(v).dtype.kind == "f"})
"""


def _columns(out, threads: str | None) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    if threads is not None:
        env["OPENBLAS_NUM_THREADS"] = threads
    scene = ROOT / "assets" / "scenes" / "table_demo.toml"
    proc = subprocess.Popen([sys.executable, "-c", CHILD, str(scene), str(out)], cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        _, err = proc.communicate(timeout=process_timeout())
    except BaseException:
        kill_tree(proc.pid)
        proc.communicate()
        raise
    assert proc.returncode == 0, err
    with np.load(out) as data:
        return {k: data[k] for k in data.files}


def test_figures_are_the_same_whatever_the_machines_cores(tmp_path):
    unset = _columns(tmp_path / "unset.npz", None)  # a user's shell: OpenBLAS would take every core
    one = _columns(tmp_path / "one.npz", "1")
    assert sorted(unset) == sorted(one) and len(one) > 5
    for key in one:
        assert np.array_equal(unset[key], one[key], equal_nan=True), key
