"""`explorer serve`: the browser explorer on http://127.0.0.1:8080 (viser, offline)."""

from __future__ import annotations

import argparse
import ipaddress
import re
import socket
import sys

from ..core.errors import InputError, check_port_number
from ..core.processes import Supervisor
from .simulate import add_scene_arguments, scene_from_args

HELP = """\
Open the 3D explorer in the browser: the cam turns, the roller, lever, spring and valve move
as computed, with plots of s, v, p and forces over the revolution and a read-out of events,
peaks and warnings. Change the scene, the lift law, speed, lash, stiffness, spring and the
effects in the side panel; every change is recomputed at once, in a child process that may take
10 s: a longer computation is stopped and the page says so, keeping the previous result. Pages
of other sites cannot connect (websocket handshakes with a foreign Origin get 403).

Every page (browser tab) has its own session by default: its own controls, results and compute
process, ended when the page closes; at most 32 pages at once. --shared gives all pages one
session instead (one person's change shows on every page); the page says which it is.

Binds 127.0.0.1 (this machine only) unless --host says otherwise. Ctrl-C (or SIGTERM, SIGHUP)
stops it cleanly: the --rerun stream is flushed and the --rerun-save file completed. A stop that
takes longer than 20 s (EXPLORER_SHUTDOWN_TIMEOUT) on a very busy machine, or a second Ctrl-C,
ends it at once; the recordings finished so far then stay beside the --rerun-save file, one
complete .rrd each.
"""


# real commands on built-in scenes; tests/test_cli_audit.py runs or parses every line
EPILOG = """\
examples:
  explorer serve
  explorer serve cycloidal_demo.toml --port 0 --paused
  explorer serve valve_float_demo.toml --rerun --rerun-save session.rrd
"""


def register(sub) -> None:
    p = sub.add_parser("serve", help="3D explorer in the browser (viser)", description=HELP,
                       epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_scene_arguments(p)
    p.add_argument("--host", default="127.0.0.1",
                   help="address to listen on (default 127.0.0.1; other hosts expose the explorer to the network)")
    p.add_argument("--port", type=int, default=8080, help="port (default 8080; the next free one if busy; 0 = any)")
    p.add_argument("--rerun", action="store_true", help="also stream every computed run to rerun (gRPC on 127.0.0.1)")
    p.add_argument("--rerun-save", metavar="PATH", help="also record every computed run into this .rrd file")
    p.add_argument("--rerun-port", type=int, default=None, metavar="N",
                   help="port of the --rerun gRPC stream on 127.0.0.1 (default 9876)")
    p.add_argument("--paused", action="store_true", help="start with the animation paused")
    share = p.add_mutually_exclusive_group()
    share.add_argument("--per-client", dest="shared", action="store_false",
                       help="every page its own controls, results and computation (the default)")
    share.add_argument("--shared", dest="shared", action="store_true",
                       help="one session for all pages: a change on one page changes every page")
    p.set_defaults(shared=False)
    p.set_defaults(run=run)


def _is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


# RFC 1123 host names: dot-separated labels of letters, digits and inner hyphens, 253 at most
_HOST_NAME = re.compile(r"(?=.{1,253}$)([A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?)(\.[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?)*\.?")


def check_host(host: str) -> None:
    """Refuse, before any server starts, a --host no socket can bind: an IP literal is checked by
    ipaddress (999.1.1.1 is none), "localhost" is taken as it is, and a name must be a host name
    that resolves (getaddrinfo: the hosts file, or DNS where there is one). Without this, viser's
    bind failure surfaced as no URL and a 20 s stop."""
    if host == "localhost":
        return
    try:
        ipaddress.ip_address(host)
    except ValueError:
        pass
    else:
        _check_bindable(host, socket.getaddrinfo(host, None, type=socket.SOCK_STREAM,
                                                 flags=socket.AI_NUMERICHOST))
        return
    if not host.strip():
        raise InputError("<command line>", "--host", "empty: give an address such as 127.0.0.1 or a host name")
    if re.fullmatch(r"[0-9.]+", host) or ":" in host:
        raise InputError("<command line>", "--host", f"{host!r} is not an IP address")
    if not _HOST_NAME.fullmatch(host):
        raise InputError("<command line>", "--host", f"{host!r} is neither an IP address nor a host name")
    try:
        infos = socket.getaddrinfo(host, None, type=socket.SOCK_STREAM)
    except (socket.gaierror, UnicodeError) as exc:
        raise InputError("<command line>", "--host", f"{host!r} does not resolve "
                         f"({exc.args[-1] if exc.args else exc})") from None
    _check_bindable(host, infos)


def _check_bindable(host: str, infos) -> None:
    """A name's addresses must include one of this machine's: bind a socket to port 0 (any free
    port, closed at once; no network traffic) on each until one takes it."""
    reason = "no address"
    for family, kind, proto, _, address in infos:
        try:
            with socket.socket(family, kind, proto) as probe:
                probe.bind((address[0], 0, *address[2:]))
            return
        except OSError as exc:
            reason = exc.strerror or str(exc)
    raise InputError("<command line>", "--host", f"{host!r} is not an address of this machine ({reason})")


def run(args) -> int:
    check_host(args.host)
    scene = scene_from_args(args)  # bad scene or --set: the usual one-line error, before any server
    check_port_number(args.port, "--port")
    if not _is_loopback(args.host):
        print(f"warning: listening on {args.host}: anyone who can reach this machine can open the explorer",
              file=sys.stderr)
    if args.rerun or args.rerun_save:
        try:
            # local: rerun is optional (the ImportError below) and loads only with --rerun
            from ..view.rerun.live import open_live_stream
        except ImportError as exc:
            raise InputError("<command line>", "--rerun", f"rerun streaming is not available ({exc})") from None

    import viser

    # local: the browser (viser, trimesh, scipy) and its threads load when the command runs
    from ..checks.viewer import evaluate as check_design
    from ..view.browser import callbacks
    from ..view.browser.app import ExplorerApp
    from ..view.browser.kernels import KernelWarmup
    from ..view.browser.sessions import PerClientExplorer

    with Supervisor("explorer serve") as supervisor:
        stream = server = app = None
        try:
            if args.rerun or args.rerun_save:
                stream = open_live_stream(args)
            server = viser.ViserServer(host=args.host, port=args.port, verbose=False)
            callbacks.use_for(server)  # idle callback threads end (the sessions' crowd leaves none behind)
            on_result = (lambda prepared: stream.log(prepared.result, prepared.label)) if stream is not None else None
            # the checks the browser computes after each result join that result's recording
            on_checked = (lambda prepared, summary: stream.log_checks(prepared.result, summary)) \
                if stream is not None else None
            # the compiled solvers are prepared once the page is served, not before (#27.2)
            kernels = KernelWarmup()
            if args.shared:
                app = ExplorerApp(server, scene.source, args.overrides, playing=not args.paused, on_result=on_result,
                                  kernels=kernels, checks=check_design, on_checked=on_checked)
            else:
                app = PerClientExplorer(server, scene.source, args.overrides, playing=not args.paused,
                                        on_result=on_result, kernels=kernels, checks=check_design,
                                        on_checked=on_checked)
            shown_host = "127.0.0.1" if args.host in ("0.0.0.0", "::") else args.host
            if not supervisor.stopping.is_set():
                print(f"Valve-Gear Explorer: http://{shown_host}:{server.get_port()}  (Ctrl-C stops)", flush=True)
                kernels.start(supervisor.spawn)
            while not supervisor.stopping.wait(0.5):
                pass
            print("stopping", file=sys.stderr)
        except KeyboardInterrupt:  # a Ctrl-C that came before the handlers were in place
            print("stopping", file=sys.stderr)
        finally:
            # in this order: no new results, no clients, then the stream completes its file
            if app is not None:
                app.stop()
            if server is not None:
                server.stop()
            if stream is not None:
                stream.close()
    return 0
