"""``--cluster`` pointed at the wrong place: one line naming the address and what is there, within
the stated connection timeout, never a hang or a traceback (issue 35: an HTTP server or a silent
listener hung 45+ s; tls://, ws:// and ucx:// gave tracebacks). Servers on loopback only."""
from __future__ import annotations

import http.server
import socket
import threading
import time

import pytest

from nbst import cluster
from nbst.cli import main
from nbst.errors import InputError

#: The connection timeout the tests state (the default is cluster.CONNECT_TIMEOUT_S = 10 s).
TIMEOUT = 1.0


@pytest.fixture
def fast(monkeypatch):
    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT_S", TIMEOUT)
    monkeypatch.setattr(cluster, "SPEAKS_FIRST_S", 0.5)


@pytest.fixture
def http_server():
    class Quiet(http.server.BaseHTTPRequestHandler):
        def do_GET(self):
            self.send_response(200)
            self.end_headers()
            self.wfile.write(b"a dashboard")

        def log_message(self, *a):
            pass

    class Server(http.server.ThreadingHTTPServer):
        def handle_error(self, request, client_address):  # a client that hangs up is no news here
            pass

    srv = Server(("127.0.0.1", 0), Quiet)
    threading.Thread(target=srv.serve_forever, daemon=True).start()
    yield f"127.0.0.1:{srv.server_address[1]}"
    srv.shutdown()
    srv.server_close()


@pytest.fixture
def silent_listener():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    s.listen(8)
    yield f"127.0.0.1:{s.getsockname()[1]}"
    s.close()


def _refused(address: str, words: str) -> float:
    t0 = time.monotonic()
    with pytest.raises(InputError) as e:
        cluster.connect(address)
    took = time.monotonic() - t0
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith(f"cluster {address}: ") and words in msg, msg
    return took


def test_an_http_server_is_named(fast, http_server):
    took = _refused(f"tcp://{http_server}", "an HTTP server")
    assert took < TIMEOUT + 1  # it is asked after the silence, not waited out


def test_a_silent_listener_is_told_within_the_timeout(fast, silent_listener):
    took = _refused(silent_listener, "says nothing")
    assert took < TIMEOUT + 1


@pytest.mark.parametrize("scheme,words", [("tls", "TLS certificates"), ("wss", "TLS certificates"),
                                          ("ucx", "UCX"), ("ws", "Dask could not connect")])
def test_other_protocols_to_the_wrong_server_are_one_line(fast, http_server, scheme, words):
    import importlib.util

    if scheme == "ucx" and importlib.util.find_spec("ucp") is not None:
        pytest.skip("ucx-py is installed here: Dask's own UCX connect answers")
    _refused(f"{scheme}://{http_server}", words)


@pytest.mark.parametrize("address,words", [("tcp://127.0.0.1:1", "connection refused"),
                                           ("tcp://no-such-host.invalid:8786", "no such host"),
                                           ("foo://127.0.0.1:8786", "unknown protocol"),
                                           ("tcp://127.0.0.1:99999", "1..65535"),
                                           ("tcp://127.0.0.1", "HOST:PORT")])
def test_addresses_that_cannot_work_are_told_at_once(fast, address, words):
    assert _refused(address, words) < TIMEOUT


def test_a_real_scheduler_still_connects():
    pytest.importorskip("distributed")
    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as lc:
        c = cluster.connect(lc.scheduler_address)
        try:
            assert c.submit(sum, [1, 2]).result() == 3
        finally:
            c.close()


def test_the_commands_say_it_in_one_line(fast, http_server, silent_listener, tmp_path, capsys):
    for argv in (["solve", "over5", "-o", str(tmp_path / "s.json"), "--cluster", http_server],
                 ["experiment", "curves", "over5", "--runs", "1", "--max-trials", "10",
                  "--out-dir", str(tmp_path / "e"), "--cluster", silent_listener]):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and "Traceback" not in err and argv[-1] in err, err
