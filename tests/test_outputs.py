"""Output paths (explorer.core.outputs): what `-o`, `--summary`, `--output-dir` and `record -o` do to
the thing they name. A regular file is replaced whole (temporary + rename) with the umask's or the
old file's mode; a symlink is followed; devices, FIFOs and /dev/stdout are written through and
stay what they were; directories, block devices, sockets and directories that take no new file
are refused before any work, in one line with exit status 2; nothing is left behind on failure.

Everything is created under tmp_path (device nodes with mknod, as root); the only system path
written is /dev/null. Blocking cases (FIFOs) run with timeouts.
"""

from __future__ import annotations

import contextlib
import os
import resource
import shutil
import signal
import socket
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from explorer import cli, load_scene
from explorer.effects.pipeline import simulate
from conftest import ROOT, SCENES

DEMO = SCENES / "cycloidal_demo.toml"
FAST = ["--set", "solver.steps_per_revolution=360"]
IS_ROOT = os.geteuid() == 0
TIMEOUT = 300


def explorer(*args, **kwargs) -> subprocess.CompletedProcess:
    if "stdout" not in kwargs and "stderr" not in kwargs:
        kwargs["capture_output"] = True
    return subprocess.run([sys.executable, "-m", "explorer", *map(str, args)], cwd=ROOT, timeout=TIMEOUT, **kwargs)


def reference_csv(tmp_path: Path) -> bytes:
    ref = tmp_path / "reference" / "ref.csv"
    ref.parent.mkdir(exist_ok=True)
    assert cli.main(["simulate", str(DEMO), *FAST, "-o", str(ref)]) == 0
    return ref.read_bytes()


@contextlib.contextmanager
def umask(mask: int):
    old = os.umask(mask)
    try:
        yield
    finally:
        os.umask(old)


def one_error_line(err: str, *needles: str) -> str:
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    assert "Traceback" not in err
    for needle in needles:
        assert needle in lines[0], lines[0]
    return lines[0]


@pytest.fixture
def no_simulation(monkeypatch):
    """Fails the test if a simulation starts: the checks must come before any work."""
    import explorer.effects.pipeline

    def refuse(*args, **kwargs):
        raise AssertionError("simulated before the output was checked")

    monkeypatch.setattr(explorer.effects.pipeline, "simulate", refuse)


# ---------------------------------------------------------------------------------------------
# regular files: mode, symlinks, nothing left behind


@pytest.mark.parametrize("mask, mode", [(0o022, 0o644), (0o077, 0o600), (0o002, 0o664)])
def test_new_files_honour_the_umask(tmp_path, mask, mode):
    csv, summary = tmp_path / "out.csv", tmp_path / "out.json"
    with umask(mask):
        assert cli.main(["simulate", str(DEMO), *FAST, "-o", str(csv), "--summary", str(summary)]) == 0
    assert stat.S_IMODE(csv.stat().st_mode) == mode
    assert stat.S_IMODE(summary.stat().st_mode) == mode
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.csv", "out.json"]


@pytest.mark.parametrize("mode", [0o444, 0o640, 0o600])
def test_a_replaced_file_keeps_its_mode(tmp_path, mode):
    """As root a 0444 file is writable (os.access says so) and is replaced; it stays 0444."""
    out = tmp_path / "out.csv"
    out.write_text("old\n")
    out.chmod(mode)
    with umask(0o022):
        code = cli.main(["simulate", str(DEMO), *FAST, "-o", str(out)])
    if not IS_ROOT and not mode & 0o200:  # as for the shell's `>`: read-only, except for root
        assert code == 2 and out.read_text() == "old\n"
        return
    assert code == 0
    assert stat.S_IMODE(out.stat().st_mode) == mode
    assert out.read_bytes() == reference_csv(tmp_path)


@pytest.mark.parametrize("sweep", [[], ["--sweep", "drive.rpm=600,1200"]])
def test_recordings_follow_the_same_mode_rules(tmp_path, sweep):
    """One recording is written by rerun into the reserved temporary, several are merged into it:
    either way a new .rrd gets the umask's mode and a replaced one keeps its own."""
    new, old = tmp_path / "new.rrd", tmp_path / "old.rrd"
    old.write_bytes(b"old")
    old.chmod(0o444 if IS_ROOT else 0o640)
    args = ["record", str(DEMO), "--no-parts", *FAST, *sweep]
    with umask(0o077):
        assert cli.main([*args, "-o", str(new)]) == 0
        assert cli.main([*args, "-o", str(old)]) == 0
    assert stat.S_IMODE(new.stat().st_mode) == 0o600
    assert stat.S_IMODE(old.stat().st_mode) == (0o444 if IS_ROOT else 0o640)
    assert old.read_bytes() != b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["new.rrd", "old.rrd"]


def test_symlink_is_followed_and_stays_a_link(tmp_path):
    target = tmp_path / "data" / "real.csv"
    target.parent.mkdir()
    target.write_text("old\n")
    target.chmod(0o640)
    link = tmp_path / "link.csv"
    link.symlink_to(target)
    assert cli.main(["simulate", str(DEMO), *FAST, "-o", str(link)]) == 0
    assert link.is_symlink() and os.readlink(link) == str(target)
    assert target.read_bytes() == reference_csv(tmp_path)
    assert stat.S_IMODE(target.stat().st_mode) == 0o640
    assert sorted(p.name for p in target.parent.iterdir()) == ["real.csv"]


def test_dangling_symlink_creates_its_target(tmp_path):
    link = tmp_path / "link.csv"
    link.symlink_to(tmp_path / "new.csv")
    assert cli.main(["simulate", str(DEMO), *FAST, "-o", str(link)]) == 0
    assert link.is_symlink() and (tmp_path / "new.csv").read_bytes() == reference_csv(tmp_path)


def test_file_size_limit_while_writing_leaves_the_old_file_and_no_temporary(tmp_path):
    """A full disk after the checks (the file-size limit stands in for it): one line, exit 2,
    the previous file as it was, no hidden temporary."""
    out = tmp_path / "out.csv"
    out.write_text("previous\n")

    def small_files():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (50_000, 50_000))

    proc = explorer("simulate", DEMO, "-o", out, preexec_fn=small_files, text=True)
    assert proc.returncode == 2
    one_error_line(proc.stderr, str(out), "--output", "File too large")
    assert out.read_text() == "previous\n"
    assert [p.name for p in tmp_path.iterdir()] == ["out.csv"]


# ---------------------------------------------------------------------------------------------
# devices, FIFOs, stdout: written through, never replaced


def test_dev_null_stays_a_device():
    before = os.stat("/dev/null")
    assert stat.S_ISCHR(before.st_mode)
    assert cli.main(["simulate", str(DEMO), *FAST, "-o", "/dev/null", "--summary", "/dev/null"]) == 0
    after = os.stat("/dev/null")
    assert stat.S_ISCHR(after.st_mode) and after.st_rdev == before.st_rdev and after.st_ino == before.st_ino


@pytest.mark.skipif(not IS_ROOT, reason="mknod needs root")
def test_character_device_node_is_written_through(tmp_path):
    """A node of /dev/null's numbers in tmp_path: the same rules as /dev/null, seen from a path we own."""
    node = tmp_path / "null"
    os.mknod(node, stat.S_IFCHR | 0o666, os.makedev(1, 3))
    assert cli.main(["simulate", str(DEMO), *FAST, "-o", str(node)]) == 0
    assert stat.S_ISCHR(node.stat().st_mode) and node.stat().st_rdev == os.makedev(1, 3)
    assert [p.name for p in tmp_path.iterdir()] == ["null"]


def test_fifo_is_written_through_and_stays_a_fifo(tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    reader = subprocess.Popen(["cat", str(fifo)], stdout=subprocess.PIPE)
    try:
        proc = explorer("simulate", DEMO, *FAST, "-o", fifo)
        data, _ = reader.communicate(timeout=TIMEOUT)
    finally:
        if reader.poll() is None:
            reader.kill()
            reader.wait()
    assert proc.returncode == 0, proc.stderr
    assert data == reference_csv(tmp_path)
    assert stat.S_ISFIFO(fifo.stat().st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pipe", "reference"]


@pytest.mark.parametrize("name", ["/dev/stdout", "-"])
def test_dev_stdout_streams_the_csv_and_reports_on_stderr(tmp_path, name):
    proc = explorer("simulate", DEMO, *FAST, "-o", name)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == reference_csv(tmp_path)
    assert b"360 steps" in proc.stderr
    assert not (ROOT / "-").exists()


def test_dev_stdout_appending_to_a_file_is_not_replaced(tmp_path):
    """`>> log`: stdout is a regular file opened for appending. /dev/stdout leads to it, but it is
    the caller's file descriptor: appended to, same inode, not renamed over."""
    log = tmp_path / "log.txt"
    log.write_bytes(b"earlier lines\n")
    inode = log.stat().st_ino
    with open(log, "ab") as handle:
        proc = explorer("simulate", DEMO, *FAST, "-o", "/dev/stdout", stdout=handle, stderr=subprocess.PIPE)
    assert proc.returncode == 0, proc.stderr
    assert log.stat().st_ino == inode
    assert log.read_bytes() == b"earlier lines\n" + reference_csv(tmp_path)


def test_record_to_dev_stdout_is_a_complete_rrd(tmp_path):
    from explorer.view.rerun.read import read_rrd

    out = tmp_path / "piped.rrd"
    with open(out, "wb") as handle:
        proc = explorer("record", DEMO, "--no-parts", *FAST, "--sweep", "drive.rpm=600,1200", "-o", "/dev/stdout",
                        stdout=handle, stderr=subprocess.PIPE)
    assert proc.returncode == 0, proc.stderr
    assert b"2 recordings" in proc.stderr
    assert len(read_rrd(out)) == 3  # the two runs and their overlay
    assert [p.name for p in tmp_path.iterdir()] == ["piped.rrd"]


# ---------------------------------------------------------------------------------------------
# refused before any work


@contextlib.contextmanager
def directory_that_takes_no_file(path: Path):
    """A directory where creating a file fails also for root: immutable (chattr +i) where that
    works, else mode 0555 for a user that is not root."""
    path.mkdir()
    if shutil.which("chattr") and subprocess.run(["chattr", "+i", str(path)], capture_output=True).returncode == 0:
        try:
            yield path
        finally:
            subprocess.run(["chattr", "-i", str(path)], check=True)
        return
    if IS_ROOT:
        pytest.skip("no way to make a directory unwritable for root here (chattr +i failed)")
    path.chmod(0o555)
    try:
        yield path
    finally:
        path.chmod(0o755)


@pytest.mark.parametrize("command", ["simulate", "summary", "record", "bench"])
def test_unwritable_directory_is_refused_before_any_work(tmp_path, capsys, no_simulation, command, monkeypatch):
    import explorer.studies.bench

    monkeypatch.setattr(explorer.studies.bench, "run_bench", lambda *a, **k: pytest.fail("benchmarked before the check"))
    with directory_that_takes_no_file(tmp_path / "ro") as ro:
        args = {"simulate": ["simulate", str(DEMO), "-o", str(ro / "out.csv")],
                "summary": ["simulate", str(DEMO), "-o", str(tmp_path / "ok.csv"), "--summary", str(ro / "s.json")],
                "record": ["record", str(DEMO), "-o", str(ro / "run.rrd")],
                "bench": ["bench", str(DEMO), "--quick", "--output-dir", str(ro)]}[command]
        assert cli.main(args) == 2
        one_error_line(capsys.readouterr().err, "not writable")
        assert list(ro.iterdir()) == []
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ro"]


@pytest.mark.parametrize("kind", ["directory", "socket", "block device", "under a file", "missing directory"])
def test_targets_that_are_never_written(tmp_path, capsys, no_simulation, kind):
    target = tmp_path / "target.csv"
    if kind == "directory":
        target.mkdir()
    elif kind == "socket":
        sock = socket.socket(socket.AF_UNIX)
        sock.bind(str(target))
        sock.close()
    elif kind == "block device":
        if not IS_ROOT:
            pytest.skip("mknod needs root")
        os.mknod(target, stat.S_IFBLK | 0o600, os.makedev(7, 200))  # a loop number nothing uses; never opened
    elif kind == "under a file":
        (tmp_path / "file").write_text("x")
        target = tmp_path / "file" / "target.csv"
    else:
        target = tmp_path / "missing" / "target.csv"
    before = sorted(p.name for p in tmp_path.iterdir())
    assert cli.main(["simulate", str(DEMO), "-o", str(target)]) == 2
    needle = {"directory": "is a directory", "socket": "is a socket", "block device": "is a block device",
              "under a file": "is not a directory", "missing directory": "does not exist"}[kind]
    one_error_line(capsys.readouterr().err, str(target), "--output", needle)
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_record_into_unwritable_directory_as_subprocess_is_one_line(tmp_path):
    """The whole command, as a user runs it: one line on stderr, exit 2, no rerun log."""
    with directory_that_takes_no_file(tmp_path / "ro") as ro:
        proc = explorer("record", DEMO, "-o", ro / "run.rrd", text=True)
        assert proc.returncode == 2
        one_error_line(proc.stderr, "--output", "not writable")
        assert proc.stdout == ""


def test_record_full_disk_is_one_line_and_keeps_the_previous_file(tmp_path):
    """A disk that fills while rerun writes: rerun only logs that in its own threads; the explorer
    says it in one line (exit 1: the input was fine) and publishes nothing."""
    out = tmp_path / "run.rrd"
    out.write_bytes(b"previous recording")

    def small_files():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (100_000, 100_000))

    for sweep in ([], ["--sweep", "drive.rpm=600,1200"]):
        proc = explorer("record", DEMO, *sweep, "-o", out, preexec_fn=small_files, text=True)
        assert proc.returncode == 1
        one_error_line(proc.stderr, str(out), "--output", "writing failed")
        assert out.read_bytes() == b"previous recording"
        assert [p.name for p in tmp_path.iterdir()] == ["run.rrd"]


# ---------------------------------------------------------------------------------------------
# the CSV in pieces


def old_csv_text(result) -> str:
    """The CSV as it was written whole before it was streamed (the reference for byte equality)."""
    names = list(result.columns)
    table = np.column_stack([np.asarray(result.columns[n], dtype=float) for n in names])
    lines = [",".join(names)]
    lines.extend(",".join(repr(float(x)) for x in row) for row in table)
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("scene", ["schenker1902_fig2.toml", "elastic_float.toml"])
def test_streamed_csv_is_byte_identical(tmp_path, scene):
    result = simulate(load_scene(SCENES / scene, ["solver.steps_per_revolution=5000",
                                                  'effects=["kinematics", "lash", "forces", "elastic"]']))
    expected = old_csv_text(result)
    assert result.csv_text() == expected
    for rows in (1, 777, 5000, 10**6):
        assert "".join(result.csv_chunks(rows)) == expected
    out = tmp_path / "out.csv"
    from explorer.core.outputs import write_output

    write_output(out, result.csv_chunks(333))
    assert out.read_text() == expected


def test_simulate_writes_the_csv_in_pieces(tmp_path, monkeypatch):
    """The command never builds the whole text (gigabytes at the largest step counts)."""
    from explorer.result import Result

    monkeypatch.setattr(Result, "csv_text", lambda self: pytest.fail("the whole CSV was built"))
    pieces = []
    real = Result.csv_chunks

    def counted(self, *args, **kwargs):
        for piece in real(self, *args, **kwargs):
            pieces.append(len(piece))
            yield piece

    monkeypatch.setattr(Result, "csv_chunks", counted)
    out = tmp_path / "out.csv"
    assert cli.main(["simulate", str(DEMO), "--set", "solver.steps_per_revolution=50000", "-o", str(out)]) == 0
    assert len(pieces) == 1 + 3  # the header, then 20 000 + 20 000 + 10 000 rows
    assert out.stat().st_size == sum(pieces)


def test_the_documented_step_maximum_holds(tmp_path, capsys):
    """The scene-file guide and the scene loader agree on the largest steps_per_revolution, and one more is a
    one-line error before any work (the maximum itself is measured in that guide, not here)."""
    from explorer.scene.scene import MAX_STEPS

    readme = (ROOT / "docs" / "guide" / "scenes.md").read_text()
    assert f"36 ... {MAX_STEPS:,}".replace(",", " ") in readme
    out = tmp_path / "out.csv"
    assert cli.main(["simulate", str(DEMO), "--set", f"solver.steps_per_revolution={MAX_STEPS + 1}", "-o", str(out)]) == 2
    one_error_line(capsys.readouterr().err, "steps_per_revolution", f"at most {MAX_STEPS}")
    assert not out.exists()
