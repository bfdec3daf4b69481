"""Connecting to a Dask scheduler: the one place for ``--cluster ADDRESS``
(``nbst experiment``, ``nbst solve``, ``nbst bowl solve|atlas``).

A wrong address gets one line within :data:`CONNECT_TIMEOUT_S` seconds (plus a second to name
what answered), never a hang or a traceback. Before Dask is asked, the address is read and the
place it names is probed with a plain socket:

* its protocol must be one this install can speak: ``tcp://`` (the default when none is given),
  ``ws://``; ``tls://`` and ``wss://`` when Dask's TLS settings name certificates
  (``distributed.comm.tls.*``); ``ucx://`` when the UCX comm is installed; ``inproc://`` (a
  scheduler inside this process) goes straight to Dask;
* something must accept a connection there (else: refused, no such host, or no answer);
* for ``tcp://``, it must speak first, as a Dask scheduler does (it sends its handshake as soon
  as a connection opens); a server silent for :data:`SPEAKS_FIRST_S` seconds is asked for an
  HTTP page, so the line can say "an HTTP server" (a Dask dashboard, say) or "something that
  says nothing".

Then ``dask.distributed.Client`` connects, under the same deadline, and any failure of its own
becomes the same kind of line (:class:`nbst.errors.InputError`, exit 2).
"""
from __future__ import annotations

import socket
import threading
import time

from nbst.errors import InputError

__all__ = ["CONNECT_TIMEOUT_S", "SPEAKS_FIRST_S", "SILENT_LIMIT_S", "SCHEMES", "split_address", "probe", "connect"]

#: Seconds a connection may take, each stage (the probe, then Dask's own connect): long enough for
#: a scheduler across a slow network, short enough that a wrong address is told within seconds.
CONNECT_TIMEOUT_S = 10.0
#: Seconds of silence after which the probe asks for an HTTP page (a Dask scheduler sends its
#: handshake within microseconds of the connection; a late one is still recognised after the ask).
SPEAKS_FIRST_S = 2.0
#: Seconds a listener that accepted the connection may stay silent, the ask included, before it is
#: told not to be a scheduler (at most the connection timeout): a scheduler has spoken long before,
#: and with the command's start-up a silent port is named within ~10 s, not 10 s after the connect.
SILENT_LIMIT_S = 6.0
#: Protocols Dask's addresses may name.
SCHEMES = ("tcp", "tls", "ws", "wss", "ucx", "inproc")
_HINT = "start one with `dask scheduler` (it prints its tcp:// address) and workers with `dask worker ADDRESS`"


def _fail(address: str, what: str) -> InputError:
    return InputError(f"cluster {address}: {what}")


def split_address(address: str) -> tuple[str, str, int]:
    """(protocol, host, port) of a Dask address (``tcp://`` when none is given); InputError (one line)
    for one nbst cannot read or whose protocol this install cannot speak."""
    a = str(address).strip()
    scheme, sep, rest = a.partition("://")
    if not sep:
        scheme, rest = "tcp", a
    scheme = scheme.lower()
    if scheme not in SCHEMES:
        raise _fail(address, f"unknown protocol {scheme!r} (Dask speaks {', '.join(s + '://' for s in SCHEMES)}); "
                             f"{_HINT}")
    if scheme == "inproc":  # a scheduler in this very process (a LocalCluster without processes): Dask checks
        return scheme, a.partition("://")[2], 0
    if scheme == "ucx":
        import importlib.util

        if not any(importlib.util.find_spec(m) is not None for m in ("ucp", "distributed_ucxx")):
            raise _fail(address, "ucx:// needs Dask's UCX comm (ucx-py), which is not installed here; give the "
                                 "scheduler's tcp:// address")
    if scheme in ("tls", "wss") and not _tls_configured():
        raise _fail(address, f"{scheme}:// needs TLS certificates (Dask's distributed.comm.tls settings), and none "
                             "are set; give a tcp:// address, or set them (docs.dask.org, 'TLS/SSL')")
    rest = rest.split("/", 1)[0]
    if rest.startswith("["):  # [IPv6]:port
        host, _, port = rest[1:].partition("]")
        port = port.lstrip(":")
    else:
        host, _, port = rest.rpartition(":")
    if not host or not port:
        raise _fail(address, f"expected {scheme}://HOST:PORT (e.g. tcp://127.0.0.1:8786)")
    try:
        p = int(port)
    except ValueError:
        p = -1
    if not 0 < p < 65536:
        raise _fail(address, f"port {port!r} is not a number in 1..65535")
    return scheme, host, p


def _tls_configured() -> bool:
    try:
        import dask

        tls = dask.config.get("distributed.comm.tls", {}) or {}
        return bool(tls.get("ca-file") or (tls.get("client") or {}).get("cert"))
    except Exception:  # noqa: BLE001 - no dask config: no certificates
        return False


def probe(address: str, *, timeout: float | None = None) -> None:
    """Check that something that may be a Dask scheduler answers at ``address`` (module doc);
    InputError (one line: the address and what is there) if not. At most ``timeout`` seconds
    (default :data:`CONNECT_TIMEOUT_S`)."""
    timeout = CONNECT_TIMEOUT_S if timeout is None else float(timeout)
    scheme, host, port = split_address(address)
    if scheme in ("ucx", "inproc"):
        return  # not a socket nbst can open: Dask's own connect, under its deadline, says what it finds
    t0 = time.monotonic()
    try:
        sock = socket.create_connection((host, port), timeout=timeout)
    except socket.gaierror:
        raise _fail(address, f"no such host {host!r}; {_HINT}") from None
    except ConnectionRefusedError:
        raise _fail(address, f"nothing listens there (connection refused); {_HINT}") from None
    except (TimeoutError, socket.timeout):
        raise _fail(address, f"no answer within {timeout:g} s (a firewall, or a host that is down)") from None
    except OSError as e:
        raise _fail(address, f"cannot connect ({e.strerror or e})") from None
    with sock:
        if scheme in ("ws", "wss"):
            return  # a web socket server waits for the client's request: Dask's connect asks
        if scheme == "tls":
            return  # the server waits for the client's TLS hello: Dask's connect, under its deadline, says
        limit = min(timeout, SILENT_LIMIT_S)
        deadline = t0 + limit
        first = _recv(sock, min(deadline, time.monotonic() + SPEAKS_FIRST_S), address)
        if first is None:  # silent so far: an HTTP server waits for a request; ask it what it is
            try:
                sock.sendall(b"GET / HTTP/1.0\r\nHost: " + host.encode("ascii", "replace") + b"\r\n\r\n")
            except OSError:
                pass
            first = _recv(sock, deadline, address)
        if first is None:
            raise _fail(address, "something there accepts connections but says nothing: no Dask handshake within "
                                 f"{limit:g} s (a Dask scheduler speaks first); {_HINT}")
        if first == b"":
            raise _fail(address, "something there accepted the connection and closed it: not a Dask scheduler; "
                                 f"{_HINT}")
        if first.startswith((b"HTTP/", b"SSH-", b"220 ", b"+OK", b"* OK")):
            kind = {b"H": "an HTTP server (a Dask dashboard, say)", b"S": "an SSH server"}.get(
                first[:1], "a mail or FTP server")
            raise _fail(address, f"{kind} answered there, not a Dask scheduler; {_HINT}")
        # it spoke first, as a Dask scheduler does


def _recv(sock, until: float, address: str) -> bytes | None:
    """The first bytes the peer sends before ``until`` (monotonic), b"" if it closed, None if silent."""
    sock.settimeout(max(0.05, until - time.monotonic()))
    try:
        return sock.recv(64)
    except (TimeoutError, socket.timeout):
        return None
    except OSError as e:
        raise _fail(address, f"the connection broke ({e.strerror or e}): not a Dask scheduler") from None


def connect(address: str, *, timeout: float | None = None):
    """A ``dask.distributed.Client`` for ``address``; InputError (a ValueError; one line naming the
    address and what is there) if no Dask scheduler answers within ``timeout`` seconds (default
    :data:`CONNECT_TIMEOUT_S`)."""
    timeout = CONNECT_TIMEOUT_S if timeout is None else float(timeout)
    probe(address, timeout=timeout)
    box: dict = {}

    def make() -> None:
        try:
            from dask.distributed import Client

            box["client"] = Client(address, timeout=f"{timeout:g}s")
        except BaseException as e:  # noqa: BLE001 - reported below, as one line
            box["error"] = e

    worker = threading.Thread(target=make, name="nbst-dask-connect", daemon=True)
    worker.start()
    deadline = time.monotonic() + timeout + 5.0  # Dask's own timeout, and its clean-up
    while worker.is_alive() and time.monotonic() < deadline:
        worker.join(0.2)  # short waits: a Ctrl-C lands in the main thread
    if worker.is_alive():
        raise _fail(address, f"Dask could not connect within {timeout:g} s; {_HINT}")
    if "error" in box:
        e = box["error"]
        if isinstance(e, KeyboardInterrupt):
            raise e
        msg = (str(e).strip().splitlines() or [""])[0][:200]
        raise _fail(address, f"Dask could not connect ({type(e).__name__}{': ' + msg if msg else ''}); "
                             f"{_HINT}") from None
    return box["client"]
