"""`serve --host` is checked before any server starts: an address no socket can bind is one line,
exit 2 (999.1.1.1 used to print nothing and take 20 s to stop). No server starts in these tests:
the bad hosts are refused before it, the good ones are checked by check_host alone."""

from __future__ import annotations


import pytest

from explorer import cli
from explorer.cli.serve import check_host

from conftest import run_cli


@pytest.mark.parametrize("host,reason", [
    ("999.1.1.1", "is not an IP address"),
    ("", "empty"),
    ("  ", "empty"),
    ("::zz", "is not an IP address"),
    ("bad_host!", "neither an IP address nor a host name"),
    ("192.0.2.1", "is not an address of this machine"),  # TEST-NET-1 (RFC 5737): never assigned
])
def test_bad_host_is_one_line_exit_2(capsys, host, reason):
    assert cli.main(["serve", "--host", host, "--port", "0"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("error: <command line>: --host: ") and reason in err[0], err


@pytest.mark.parametrize("host", ["127.0.0.1", "localhost", "0.0.0.0"])
def test_loopback_and_any_are_accepted(host):
    check_host(host)


def test_bad_host_in_a_subprocess_ends_at_once():
    proc = run_cli("serve", "--host", "999.1.1.1", "--port", "0", timeout=60)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.strip() == "error: <command line>: --host: '999.1.1.1' is not an IP address"
