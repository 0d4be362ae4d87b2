"""The viewer's web server as a contract: what `skyscatter.viewer.server`'s docstring and HTTP
promise about binding, static files, bad parameters, methods, sizes, concurrent table requests,
writes and the sun's position.

Each test starts its own server on a free loopback port (`server` fixture) and talks to it with
http.client, or with a raw socket where the exact request line matters (http.client would send
what it is given too, but a socket leaves no doubt). No test asks for the real full-quality
tables (about 45 s): the table tests use `quality=preview`, a cheap QUALITIES table, or a
monkeypatched `TableService.spectral_tables`.
"""

from __future__ import annotations

import http.client
import json
import math
import os
import re
import socket
import threading
import time
from pathlib import Path
from types import SimpleNamespace

import pytest

from skyscatter import api
from skyscatter.cli import main
from skyscatter.errors import InputError
from skyscatter.transport.cache import TableCache
from skyscatter.transport.code_fingerprint import MEMO_FILE
from skyscatter.viewer import server as server_module
from skyscatter.viewer import table_service
from skyscatter.viewer.server import (
    CLIENT_HEADER,
    MAX_FIELDS,
    MAX_URL,
    STATIC_DIR,
    TOKEN_HEADER,
    make_server,
    static_files,
)
from skyscatter.viewer.table_service import TableService

PACKAGE_DIR = Path(server_module.__file__).resolve().parents[1]  # src/skyscatter
SERVER_SOURCE = Path(server_module.__file__).read_bytes()
# text that only server.py holds, and text of every /etc/passwd
LEAK_MARKERS = [b"BaseHTTPRequestHandler", b"def _refuse_method", b"root:x:0:0", b"/bin/sh"]
BERLIN_NOON = "/api/sky?time=2024-06-21T12:00Z&lat=52.52&lon=13.40"


@pytest.fixture
def server(tmp_path):
    """A running viewer server for `earth`, its table cache in tmp_path/cache."""
    viewer = api.viewer_server("earth", cache_dir=tmp_path / "cache")
    thread = threading.Thread(target=viewer.serve_forever, kwargs={"poll_interval": 0.02},
                              daemon=True)  # shutdown() waits up to one poll interval
    thread.start()
    yield viewer
    viewer.shutdown()
    viewer.server_close()
    thread.join(timeout=10)


def request(server, path: str, method: str = "GET", body: bytes | None = None,
            headers: dict | None = None, timeout: float = 60.0):
    """(status, headers, body) of one request through http.client, with the server's token
    (the page's header) unless `headers` gives another."""
    connection = http.client.HTTPConnection("127.0.0.1", server.server_address[1],
                                            timeout=timeout)
    try:
        connection.request(method, path, body=body,
                           headers={TOKEN_HEADER: server.token, **(headers or {})})
        response = connection.getresponse()
        return response.status, response.headers, response.read()
    finally:
        connection.close()


def raw_exchange(server, data: bytes, timeout: float = 20.0) -> bytes:
    """Everything the server sends back for the raw bytes `data`, until it closes."""
    chunks = []
    with socket.create_connection(("127.0.0.1", server.server_address[1]),
                                  timeout=timeout) as sock:
        sock.sendall(data)
        try:
            while chunk := sock.recv(65536):
                chunks.append(chunk)
        except ConnectionResetError:  # closed with our unread bytes still queued
            pass
    return b"".join(chunks)


def host(server) -> bytes:
    """The Host header line a browser sends to `server`, and the token header."""
    return b"Host: 127.0.0.1:%d\r\n%s: %s\r\n" % (server.server_address[1], TOKEN_HEADER.encode(),
                                                 server.token.encode())


def raw_get(server, target: str | bytes, method: bytes = b"GET") -> bytes:
    """The raw answer to `METHOD target HTTP/1.1`, the target sent byte for byte."""
    target = target.encode() if isinstance(target, str) else target
    return raw_exchange(server, method + b" " + target + b" HTTP/1.1\r\n" + host(server)
                        + b"Connection: close\r\n\r\n")


def parse_response(data: bytes) -> tuple[int, dict[str, str], bytes]:
    """(status, headers with lower-case names, body) of the first response in `data`."""
    head, _, rest = data.partition(b"\r\n\r\n")
    lines = head.decode("latin-1").split("\r\n")
    match = re.fullmatch(r"HTTP/1\.[01] (\d{3})( .*)?", lines[0])
    assert match, f"no HTTP status line: {data[:200]!r}"
    headers = {}
    for line in lines[1:]:
        name, _, value = line.partition(":")
        headers[name.strip().lower()] = value.strip()
    return int(match.group(1)), headers, rest[:int(headers.get("content-length", len(rest)))]


def count_responses(data: bytes) -> int:
    return len(re.findall(rb"(?:^|\r\n\r\n|})HTTP/1\.[01] \d{3} ", data))


def json_error(status_headers_body) -> str:
    """The message of a JSON error answer, checking that it is one."""
    _, headers, body = status_headers_body
    assert headers["content-type"].startswith("application/json")
    value = json.loads(body)
    assert set(value) == {"error"} and isinstance(value["error"], str) and value["error"]
    return value["error"]


def wait_for(condition, seconds: float = 20.0) -> None:
    deadline = time.monotonic() + seconds
    while not condition():
        assert time.monotonic() < deadline, "timed out waiting"
        time.sleep(0.01)


def snapshot(directory: Path, skip: str | None = None) -> dict[str, tuple[int, int]]:
    """relative path -> (size, mtime_ns) of every file under `directory` ({} if missing)."""
    if not directory.exists():
        return {}
    return {path.relative_to(directory).as_posix(): (path.stat().st_size,
                                                     path.stat().st_mtime_ns)
            for path in directory.rglob("*")
            if path.is_file() and not (skip and skip in path.parts)}


def table_entries(cache_dir: Path) -> dict[str, tuple[int, int]]:
    """`snapshot` of the scattering tables' entries in a cache folder (not the Mie tables'
    subfolder, nor the memo of the tables' code fingerprint)."""
    return {name: stat for name, stat in snapshot(cache_dir, skip="mie").items()
            if name != MEMO_FILE}


# 1. Binding ------------------------------------------------------------------------------------

def test_binds_loopback_on_a_free_port_by_default():
    viewer = api.viewer_server()
    try:
        host, port = viewer.server_address[:2]
        assert host == "127.0.0.1"
        assert 0 < port <= 65535
        assert viewer.url == f"http://127.0.0.1:{port}/?token={viewer.token}"
        assert len(viewer.token) >= 40  # 32 random bytes, URL-safe base64
    finally:
        viewer.server_close()
    viewer = make_server(TableService(), lambda *args: (0.0, 0.0, ""))
    try:
        assert viewer.server_address[0] == "127.0.0.1" and viewer.server_address[1] > 0
    finally:
        viewer.server_close()


def test_port_in_use_is_an_input_error_naming_the_port():
    with socket.socket() as blocker:
        blocker.bind(("127.0.0.1", 0))
        blocker.listen()
        port = blocker.getsockname()[1]
        with pytest.raises(InputError, match=str(port)) as caught:
            api.viewer_server(port=port)
        assert caught.value.key == "port"


@pytest.mark.parametrize("port", [-1, 65536, 70000, "8080", 1.5])
def test_bad_port_is_an_input_error_naming_the_port(port):
    with pytest.raises(InputError, match=re.escape(repr(port))) as caught:
        make_server(TableService(), lambda *args: (0.0, 0.0, ""), port=port)
    assert caught.value.key == "port"
    assert "port" in str(caught.value)


@pytest.fixture
def fake_serve_forever(monkeypatch):
    """`serve_forever` returning at once (it closes the server, as the real one does)."""
    calls = []

    def serve_forever(server, open_browser):
        calls.append((server.server_address[:2], open_browser))
        server.server_close()

    monkeypatch.setattr(server_module, "serve_forever", serve_forever)
    return calls


def test_cli_view_off_loopback_warns(fake_serve_forever, capsys, tmp_path):
    code = main(["view", "--host", "0.0.0.0", "--no-browser", "--cache-dir", str(tmp_path)])
    out, err = capsys.readouterr()
    assert code == 0
    [((host, port), open_browser)] = fake_serve_forever
    assert (host, open_browser) == ("0.0.0.0", False) and port > 0
    assert re.search(rf"skyscatter viewer: http://0\.0\.0\.0:{port}/\?token=[\w-]{{40,}} ", out)
    assert "WARNING" in err and "0.0.0.0" in err and "anyone" in err and "token" in err


def test_cli_view_off_loopback_warns_even_when_quiet(fake_serve_forever, capfd, tmp_path):
    """--quiet silences notes and progress, not the warning that the network can reach it."""
    code = main(["--quiet", "view", "--host", "0.0.0.0", "--no-browser",
                 "--cache-dir", str(tmp_path)])
    out, err = capfd.readouterr()
    assert code == 0 and "skyscatter viewer: http://0.0.0.0:" in out
    assert "WARNING" in err and "anyone" in err


def test_cli_view_on_loopback_does_not_warn(fake_serve_forever, capsys, tmp_path):
    code = main(["view", "--no-browser", "--cache-dir", str(tmp_path)])
    out, err = capsys.readouterr()
    assert code == 0
    [((host, port), open_browser)] = fake_serve_forever
    assert (host, open_browser) == ("127.0.0.1", False) and port > 0
    assert re.search(rf"^skyscatter viewer: http://127\.0\.0\.1:{port}/\?token=[\w-]{{40,}} ",
                     out, re.M)
    assert "warning" not in err.lower()


def test_cli_view_bad_port_exits_2_naming_it(fake_serve_forever, capsys):
    try:  # refused by the option parser (SystemExit) or by the server (returned)
        code = main(["view", "--no-browser", "--port", "70000"])
    except SystemExit as stop:
        code = stop.code
    _, err = capsys.readouterr()
    assert code == 2 and "70000" in err and "Traceback" not in err
    assert not fake_serve_forever


@pytest.mark.parametrize("host", ["127.0.0.1", "127.0.0.2", "::1", "localhost"])
def test_is_loopback(host):
    assert api.is_loopback(host)


@pytest.mark.parametrize("host", ["0.0.0.0", "::", "", "192.168.1.2", "example.org"])
def test_is_not_loopback(host):
    assert not api.is_loopback(host)


# 2. Static files -------------------------------------------------------------------------------

@pytest.mark.parametrize(("path", "file", "content_type"), [
    ("/", "index.html", "text/html"),
    ("/static/viewer.js", "viewer.js", "text/javascript"),
    ("/static/shaders/sky.glsl", "shaders/sky.glsl", "text/plain"),
    ("/static/generated/lut_layout.json", "generated/lut_layout.json", "application/json"),
])
def test_static_files_are_served(server, path, file, content_type):
    status, headers, body = request(server, path)
    assert status == 200
    assert headers["Content-Type"].split(";")[0].strip() == content_type
    assert body == (STATIC_DIR / file).read_bytes()
    assert headers["X-Content-Type-Options"] == "nosniff"
    if path.endswith(".json"):
        json.loads(body)


def test_head_sends_headers_without_body(server):
    answer = raw_get(server, "/static/viewer.js", method=b"HEAD")
    status, headers, body = parse_response(answer)
    assert status == 200
    assert int(headers["content-length"]) == len((STATIC_DIR / "viewer.js").read_bytes())
    assert body == b""


TRAVERSALS = [
    "/static/../server.py", "/static/..%2fserver.py", "/static/%2e%2e/server.py",
    "/static/%2e%2e%2fserver.py", "/static/.%2e/server.py", "/static/..%5cserver.py",
    "/static/..\\server.py", "/static//etc/passwd", "/static/../../../../etc/passwd",
    "/static/%2e%2e/%2e%2e/%2e%2e/%2e%2e/etc/passwd", "/static/shaders/../../server.py",
    "/static/viewer.js/../../server.py", "/static/./../server.py",
    "/static/" + str(Path(server_module.__file__).resolve()), "/static/" + "/etc/passwd",
    "/etc/passwd", "//etc/passwd", "/../server.py", "/static/", "/static/shaders",
    "http://127.0.0.1/static/../server.py", "http://127.0.0.1/etc/passwd",
    "/static/%00../server.py", "/static/shaders%2f..%2f..%2fserver.py",
]


@pytest.mark.parametrize("target", TRAVERSALS)
def test_path_traversal_is_404_and_leaks_nothing(server, target):
    answer = raw_get(server, target)
    status, _, body = parse_response(answer)
    assert status == 404
    json_error(parse_response(answer))
    for marker in LEAK_MARKERS:
        assert marker not in answer
    assert SERVER_SOURCE[:200] not in answer


def test_static_files_skips_symlinks(tmp_path):
    root = tmp_path / "static"
    (root / "sub").mkdir(parents=True)
    (root / "page.js").write_text("page")
    (root / "sub" / "nested.glsl").write_text("nested")
    outside = tmp_path / "secret"
    outside.mkdir()
    (outside / "key.txt").write_text("secret")
    (root / "link.txt").symlink_to(outside / "key.txt")
    (root / "linkdir").symlink_to(outside, target_is_directory=True)
    (root / "dangling").symlink_to(tmp_path / "nothing")
    files = static_files(root)
    assert set(files) == {"page.js", "sub/nested.glsl"}
    assert all(path.resolve().is_relative_to(root.resolve()) for path in files.values())


def test_served_files_are_the_static_directory_only(server):
    assert set(server.files) == set(static_files(STATIC_DIR))
    assert all(path.resolve().is_relative_to(STATIC_DIR.resolve())
               for path in server.files.values())


# 3. Bad parameters -----------------------------------------------------------------------------

TOO_MANY = "&".join(f"amount_air={i}" if i == 0 else f"field{i}=1" for i in range(MAX_FIELDS + 1))
BAD_TABLE_QUERIES = [
    ("albedo=3", "albedo"), ("albedo=nan", "albedo"), ("albedo=abc", "albedo"),
    ("albedo=inf", "albedo"), ("albedo=", "albedo"),
    ("atmosphere=nonexistent", "atmosphere"), ("quality=ultra", "quality"),
    ("amount_air=-1", "amount_air"), ("amount_air=21", "amount_air"),
    ("amount_nosuch=1", "amount_nosuch"), ("bogus=1", "bogus"),
    (TOO_MANY, str(MAX_FIELDS)),
]


@pytest.mark.parametrize(("query", "named"), BAD_TABLE_QUERIES,
                         ids=[q[:30] for q, _ in BAD_TABLE_QUERIES])
def test_bad_table_parameter_is_400_naming_it(server, query, named):
    answer = request(server, f"/api/tables?{query}")
    assert answer[0] == 400
    assert named in json_error(answer)


def test_repeated_parameter_is_400(server):
    answer = request(server, "/api/tables?albedo=0.1&albedo=0.2")
    assert answer[0] == 400
    assert "twice" in json_error(answer)


def test_repeated_parameter_message_names_it(server):
    assert "albedo" in json_error(request(server, "/api/tables?albedo=0.1&albedo=0.2"))


BAD_SKY_QUERIES = [
    ("lat=52.5&lon=13.4", "time"),
    ("time=2024-06-21T12:00&lat=52.5&lon=13.4", "time zone"),
    ("time=2024-06-21T12:00Z&lat=95&lon=13.4", "latitude"),
    ("time=2024-06-21T12:00Z&lat=nan&lon=13.4", "latitude"),
    ("time=2024-06-21T12:00Z&lat=52.5&lon=inf", "longitude"),
    ("time=2024-06-21T12:00Z&lat=north&lon=13.4", "lat"),
    ("time=yesterday&lat=52.5&lon=13.4", "time"),
    ("time=2024-06-21T12:00Z&lat=52.5&lon=13.4&zoom=2", "zoom"),
    ("time=2024-06-21T12:00Z&lat=52.5&lon=13.4&atmosphere=nonexistent", "atmosphere"),
    ("time=2024-06-21T12:00Z&lat=52.5&lon=13.4&atmosphere=exo-hazy", "ephemeris"),
]


@pytest.mark.parametrize(("query", "named"), BAD_SKY_QUERIES,
                         ids=[n for _, n in BAD_SKY_QUERIES])
def test_bad_sky_parameter_is_400_with_a_message(server, query, named):
    answer = request(server, f"/api/sky?{query}")
    assert answer[0] == 400
    assert named in json_error(answer)


def test_server_keeps_running_after_bad_requests(server):
    """Bad requests on one kept-alive connection, then the atmospheres on a new one."""
    connection = http.client.HTTPConnection("127.0.0.1", server.server_address[1], timeout=60)
    try:
        for query, _ in BAD_TABLE_QUERIES:
            connection.request("GET", f"/api/tables?{query}",
                               headers={TOKEN_HEADER: server.token})
            response = connection.getresponse()
            response.read()
            assert response.status == 400
        for query, _ in BAD_SKY_QUERIES:
            connection.request("GET", f"/api/sky?{query}",
                               headers={TOKEN_HEADER: server.token})
            response = connection.getresponse()
            response.read()
            assert response.status == 400
    finally:
        connection.close()
    raw_exchange(server, b"GET / HTTP/1.1 extra\r\nHost: x\r\n\r\n")  # malformed request line
    raw_exchange(server, b"\x16\x03\x01\x00\xa5\x01\x00\x00\xa1\x03\x03" + bytes(200)
                 + b"\r\n\r\n")  # a TLS hello
    status, _, body = request(server, "/api/atmospheres")
    assert status == 200
    described = json.loads(body)
    assert described["default"] == "earth"
    assert "earth" in {entry["name"] for entry in described["atmospheres"]}


# 4. Methods and sizes --------------------------------------------------------------------------

@pytest.mark.parametrize("method", ["POST", "PUT", "DELETE", "PATCH", "OPTIONS"])
@pytest.mark.parametrize("path", ["/", "/api/tables"])
def test_other_methods_are_405_with_allow(server, method, path):
    answer = request(server, path, method=method)
    assert answer[0] == 405
    assert {value.strip() for value in answer[1]["Allow"].split(",")} == {"GET", "HEAD"}
    assert method in json_error(answer)


def test_get_with_a_body_is_413(server):
    answer = request(server, "/api/atmospheres", body=b"0123456789",
                     headers={"Content-Length": "10"})
    assert answer[0] == 413
    json_error(answer)


def test_get_with_a_chunked_body_is_413(server):
    status, headers, _ = parse_response(raw_exchange(
        server, b"GET / HTTP/1.1\r\n" + host(server)
        + b"Transfer-Encoding: chunked\r\n\r\n0\r\n\r\n"))
    assert status == 413


SMUGGLED = b"GET /smuggled HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n"
AFTER = b"GET /after HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n"


def test_body_of_a_refused_get_is_not_read_as_a_request(server):
    answer = raw_exchange(server, b"GET / HTTP/1.1\r\n" + host(server)
                          + b"Content-Length: %d\r\n\r\n" % len(SMUGGLED) + SMUGGLED + AFTER)
    assert parse_response(answer)[0] == 413
    assert b"/smuggled" not in answer and count_responses(answer) == 1


def test_body_of_a_refused_post_is_not_read_as_a_request(server):
    answer = raw_exchange(server, b"POST /api/tables HTTP/1.1\r\n" + host(server)
                          + b"Content-Length: %d\r\n\r\n" % len(SMUGGLED) + SMUGGLED + AFTER)
    assert parse_response(answer)[0] == 405
    assert b"/smuggled" not in answer


def test_request_line_over_the_limit_is_414(server):
    target = "/api/tables?albedo=0.5&" + "x" * MAX_URL
    answer = raw_get(server, target)
    assert parse_response(answer)[0] == 414
    assert str(MAX_URL) in json_error(parse_response(answer))
    assert parse_response(raw_get(server, "/nosuch?" + "x" * (MAX_URL - 100)))[0] == 404


@pytest.mark.parametrize("path", ["/nosuch", "/api", "/api/tables/", "/API/atmospheres",
                                  "/index.htm", "*"])
def test_unknown_path_is_404_json(server, path):
    answer = parse_response(raw_get(server, path))
    assert answer[0] == 404
    json_error(answer)


STDLIB_ERRORS = {
    "request line over 64 KiB (414)": (b"GET /" + b"a" * 70000 + b" HTTP/1.1\r\nHost: x\r\n\r\n",
                                       414),
    "over 100 headers (431)": (b"GET / HTTP/1.1\r\n" + b"".join(b"X-%d: 1\r\n" % i
                                                               for i in range(120)) + b"\r\n",
                               431),
    "TRACE (501)": (b"TRACE / HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n", 501),
    "malformed request line (400)": (b"GET / HTTP/1.1 extra\r\nHost: x\r\n\r\n", 400),
}


@pytest.mark.parametrize("case", list(STDLIB_ERRORS))
def test_every_error_is_json(server, case):
    data, status = STDLIB_ERRORS[case]
    answer = parse_response(raw_exchange(server, data))
    assert answer[0] == status
    json_error(answer)


# 5. Concurrency --------------------------------------------------------------------------------

@pytest.fixture
def blocked_tables(monkeypatch):
    """Table computations that wait for `release` (then report progress, as the real one does,
    and give the label as the message); `started` lists the requests computed."""
    release = threading.Event()
    started = []

    def spectral_tables(self, request, progress=None):
        started.append(request)
        assert release.wait(30)
        progress(1, 1, "test")
        return self.atmosphere(request.atmosphere), None, SimpleNamespace(scattering_names=())

    monkeypatch.setattr(TableService, "spectral_tables", spectral_tables)
    monkeypatch.setattr(table_service, "gpu_tables", lambda tables, profile, star, label: label)
    monkeypatch.setattr(table_service, "encode", lambda label: label.encode())
    yield SimpleNamespace(release=release, started=started)
    release.set()


def fetch_in_thread(server, path: str) -> tuple[threading.Thread, list]:
    result = []
    thread = threading.Thread(target=lambda: result.append(request(server, path, timeout=30)),
                              daemon=True)
    thread.start()
    return thread, result


def test_newer_table_request_supersedes_the_running_one(server, blocked_tables):
    first, first_result = fetch_in_thread(server, "/api/tables?albedo=0.1")
    wait_for(lambda: len(blocked_tables.started) == 1)
    status, _, body = request(server, "/api/progress")  # answered while it computes
    assert status == 200 and json.loads(body)["busy"] is True
    second, second_result = fetch_in_thread(server, "/api/tables?albedo=0.2")
    wait_for(lambda: server.service._waiting == 2)
    blocked_tables.release.set()
    first.join(30)
    second.join(30)
    assert first_result[0][0] == 409
    assert "newer" in json_error(first_result[0])
    assert second_result[0][0] == 200
    assert second_result[0][2] == b"earth (preview)"
    assert [r.albedo for r in blocked_tables.started] == [0.1, 0.2]
    assert json.loads(request(server, "/api/progress")[2])["busy"] is False


def test_too_many_waiting_table_requests_get_429(server, blocked_tables):
    threads = []
    for i in range(1 + table_service.MAX_WAITING):  # one computing, MAX_WAITING waiting
        threads.append(fetch_in_thread(server, f"/api/tables?albedo=0.{i + 1}"))
        wait_for(lambda n=i + 1: server.service._waiting == n)
    wait_for(lambda: len(blocked_tables.started) == 1)
    extra = request(server, "/api/tables?albedo=0.9", timeout=10)
    assert extra[0] == 429
    assert int(extra[1]["Retry-After"]) >= 1
    json_error(extra)
    blocked_tables.release.set()
    for thread, _ in threads:
        thread.join(30)
    statuses = [result[0][0] for _, result in threads]
    assert statuses == [409] * table_service.MAX_WAITING + [200]
    assert len(blocked_tables.started) == 1 + 1  # the first, then the newest only
    assert server.service._waiting == 0
    assert request(server, "/api/tables?albedo=0.9")[0] == 200  # no longer busy


# 6. Writes -------------------------------------------------------------------------------------

def test_preview_tables_write_nothing(server, tmp_path, monkeypatch):
    cwd = tmp_path / "cwd"
    cwd.mkdir()
    monkeypatch.chdir(cwd)
    cache = tmp_path / "cache"
    default_cache = Path(os.environ["SKYSCATTER_CACHE_DIR"])
    places = [cache, cwd, default_cache]
    before = [snapshot(place) for place in places]
    package_before = set(snapshot(PACKAGE_DIR, skip="__pycache__"))
    status, headers, body = request(server, "/api/tables?atmosphere=earth&quality=preview")
    assert status == 200
    assert headers["Content-Type"] == "application/octet-stream"
    assert body[:4] == b"SKYT"
    assert [snapshot(place) for place in places] == before
    assert set(snapshot(PACKAGE_DIR, skip="__pycache__")) == package_before
    assert request(server, "/api/tables?quality=preview")[2] == body  # kept in memory


def test_full_tables_write_only_into_the_cache_dir(server, tmp_path, monkeypatch):
    monkeypatch.setattr(table_service, "QUALITIES", {"preview": (4, 0.25), "full": (4, 0.3)})
    cwd = tmp_path / "cwd"
    cwd.mkdir()
    monkeypatch.chdir(cwd)
    cache = tmp_path / "cache"
    default_cache = Path(os.environ["SKYSCATTER_CACHE_DIR"])
    before = [snapshot(place) for place in (cwd, default_cache)]
    package_before = set(snapshot(PACKAGE_DIR, skip="__pycache__"))
    status, _, body = request(server, "/api/tables?quality=full")
    assert status == 200 and body[:4] == b"SKYT"
    written = snapshot(cache)
    # cache entries, and the memo of the tables' code fingerprint
    assert written and all(re.fullmatch(r"[\w-]+\.npz", name) or name == MEMO_FILE
                           for name in written), written
    assert [snapshot(place) for place in (cwd, default_cache)] == before
    assert set(snapshot(PACKAGE_DIR, skip="__pycache__")) == package_before


def test_loading_an_atmosphere_writes_only_into_the_cache_dir(server, tmp_path, monkeypatch):
    default_cache = tmp_path / "default-cache"  # fresh: nothing cached there yet
    monkeypatch.setenv("SKYSCATTER_CACHE_DIR", str(default_cache))
    answer = request(server, "/api/sky?time=2024-06-21T12:00Z&lat=0&lon=0&atmosphere=exo-hazy")
    assert answer[0] == 400  # no ephemeris, but the atmosphere was loaded
    assert snapshot(default_cache) == {}


# 7. The sun ------------------------------------------------------------------------------------

def test_sun_position_agrees_with_pyephem(server):
    ephem = pytest.importorskip("ephem")
    status, _, body = request(server, BERLIN_NOON)
    assert status == 200
    sky = json.loads(body)
    assert sky["time_utc"] == "2024-06-21T12:00:00+00:00"
    observer = ephem.Observer()
    observer.lat, observer.lon = "52.52", "13.40"
    observer.elevation = 0.0
    # the viewer's sun is the apparent one, refracted by standard air (1010 hPa, 10 C, as
    # render.sky_at_time draws it); PyEphem refracts with the same air. 0.005 deg: the two
    # refraction formulas differ by less than 1e-3 deg at 59 deg altitude
    observer.pressure, observer.temp = 1010.0, 10.0
    observer.date = "2024/6/21 12:00:00"
    sun = ephem.Sun(observer)
    assert abs(sky["sun_zenith_deg"] - (90.0 - math.degrees(sun.alt))) < 0.005
    assert abs(sky["sun_azimuth_deg"] - math.degrees(sun.az)) < 0.05
    # the sun's light at its distance that day over 1 AU (the earth preset's): PyEphem's
    # Earth-Sun distance (geocentric; ours is topocentric, 4.3e-5 closer at most), so 1e-4
    assert sky["sun_light_scale"] == pytest.approx(1.0 / sun.earth_distance**2, rel=1e-4)
    assert sky["sun_light_scale"] < 0.97  # near aphelion: 3 % less light


# 8. Who may ask: Host, Origin, token ------------------------------------------------------------

@pytest.fixture
def counted_tables(monkeypatch):
    """Table requests answered at once with a fake message; the list of those computed."""
    started = []

    def tables(self, request, client=""):
        started.append((request, client))
        return b"SKYT fake"

    monkeypatch.setattr(TableService, "tables", tables)
    return started


def answer_with(server, target: str, headers: dict[str, str]) -> tuple[int, dict, bytes]:
    """The parsed answer to GET `target` with exactly these headers (no others)."""
    lines = "".join(f"{name}: {value}\r\n" for name, value in headers.items())
    return parse_response(raw_exchange(
        server, f"GET {target} HTTP/1.1\r\n{lines}Connection: close\r\n\r\n".encode()))


FORGED_HOSTS = ["evil.example:{port}", "evil.example", "127.0.0.1.evil.example:{port}",
                "localhost.evil.example:{port}", "127.0.0.1:{other}", "localhost:{other}",
                "127.0.0.1", "user@127.0.0.1:{port}", "127.0.0.1:{port}/x", "", "[::1",
                "10.0.0.1:{port}"]


@pytest.mark.parametrize("forged", FORGED_HOSTS)
@pytest.mark.parametrize("target", ["/api/tables?quality=preview", "/api/progress", "/"])
def test_forged_host_is_refused_before_any_work(server, counted_tables, forged, target):
    """A Host that is not this server's address and port (what a page of another site sends
    after rebinding its DNS name to 127.0.0.1), with the right token even: 421, nothing
    computed."""
    port = server.server_address[1]
    host = forged.format(port=port, other=port + 1 if port < 65535 else port - 1)
    answer = answer_with(server, target, {"Host": host, TOKEN_HEADER: server.token})
    assert answer[0] == 421
    assert "host" in json_error(answer)
    assert counted_tables == []


def test_missing_or_repeated_host_is_refused(server, counted_tables):
    answer = answer_with(server, "/api/tables", {TOKEN_HEADER: server.token})
    assert answer[0] == 421 and counted_tables == []
    twice = raw_exchange(server, b"GET /api/tables HTTP/1.1\r\n" + host(server)
                         + b"Host: evil.example\r\nConnection: close\r\n\r\n")
    assert parse_response(twice)[0] == 421 and counted_tables == []


def test_dns_rebinding_is_refused(server, counted_tables):
    """The rebinding attack itself: the browser connects to 127.0.0.1 (the attacker's name
    now resolves there) and sends the attacker's name as Host; its page cannot know the token
    and its fetch carries its own Origin. Refused whichever of the three it gets right."""
    port = server.server_address[1]
    for headers in ({"Host": f"evil.example:{port}"},
                    {"Host": f"evil.example:{port}", "Origin": f"http://evil.example:{port}"},
                    {"Host": f"evil.example:{port}", TOKEN_HEADER: server.token}):
        status, _, _ = answer_with(server, "/api/tables?quality=full", headers)
        assert status == 421
    assert counted_tables == []


@pytest.mark.parametrize("host", ["127.0.0.1:{port}", "localhost:{port}", "LocalHost:{port}",
                                  "[::1]:{port}"])
def test_own_host_names_are_served(server, counted_tables, host):
    port = server.server_address[1]
    status, _, body = answer_with(server, "/api/tables?quality=preview",
                                  {"Host": host.format(port=port), TOKEN_HEADER: server.token})
    assert status == 200 and body == b"SKYT fake"


@pytest.mark.parametrize("origin", ["http://evil.example", "http://evil.example:{port}",
                                    "null", "http://127.0.0.1:{other}", "https://127.0.0.1:{port}",
                                    "http://localhost:{port}", "file://"])
def test_foreign_origin_is_refused_before_any_work(server, counted_tables, origin):
    """A cross-origin request (another site's page, a sandboxed frame, another port, or the
    other loopback name than the page's own): 403, nothing computed."""
    port = server.server_address[1]
    answer = answer_with(server, "/api/tables?quality=preview", {
        "Host": f"127.0.0.1:{port}", TOKEN_HEADER: server.token,
        "Origin": origin.format(port=port, other=port + 1 if port < 65535 else port - 1)})
    assert answer[0] == 403
    assert "refused" in json_error(answer)
    assert counted_tables == []


def test_own_origin_is_served(server, counted_tables):
    port = server.server_address[1]
    status, _, _ = answer_with(server, "/api/tables", {
        "Host": f"127.0.0.1:{port}", "Origin": f"http://127.0.0.1:{port}",
        TOKEN_HEADER: server.token})
    assert status == 200 and len(counted_tables) == 1


@pytest.mark.parametrize("token", [None, "", "wrong", "x" * 43, "{token}x", "{token_prefix}"])
@pytest.mark.parametrize("route", ["/api/tables?quality=preview", "/api/progress",
                                   "/api/atmospheres", BERLIN_NOON, "/api/nosuch"])
def test_missing_or_wrong_token_is_403_before_any_work(server, counted_tables, token, route):
    port = server.server_address[1]
    headers = {"Host": f"127.0.0.1:{port}"}
    if token is not None:
        headers[TOKEN_HEADER] = token.format(token=server.token, token_prefix=server.token[:-1])
    answer = answer_with(server, route, headers)
    assert answer[0] == 403
    assert "token" in json_error(answer)
    assert counted_tables == []


def test_token_in_the_query_or_header_is_accepted(server, counted_tables):
    port = server.server_address[1]
    host = {"Host": f"127.0.0.1:{port}"}
    assert answer_with(server, f"/api/tables?token={server.token}", host)[0] == 200
    assert answer_with(server, "/api/tables", {**host, TOKEN_HEADER: server.token})[0] == 200
    assert answer_with(server, "/api/tables?token=wrong", host)[0] == 403
    assert len(counted_tables) == 2


def test_the_page_and_its_files_need_no_token(server):
    """The printed address (/?token=...) and the static files load without a token header;
    only the API needs it."""
    port = server.server_address[1]
    host = {"Host": f"127.0.0.1:{port}"}
    assert answer_with(server, f"/?token={server.token}", host)[0] == 200
    assert answer_with(server, "/static/viewer.js", host)[0] == 200


def test_every_launch_has_its_own_token():
    servers = [api.viewer_server() for _ in range(3)]
    try:
        assert len({viewer.token for viewer in servers}) == 3
    finally:
        for viewer in servers:
            viewer.server_close()


@pytest.mark.parametrize(("header", "bound", "allowed"), [
    ("127.0.0.1:8080", "127.0.0.1", True), ("localhost:8080", "127.0.0.1", True),
    ("[::1]:8080", "::1", True), ("192.168.1.2:8080", "192.168.1.2", True),
    ("192.168.1.2:8080", "127.0.0.1", False), ("192.168.1.2:8080", "0.0.0.0", True),
    ("[fe80::1]:8080", "::", True), ("evil.example:8080", "0.0.0.0", False),
    ("viewer.lan:8080", "viewer.lan", True), ("viewer.lan:8081", "viewer.lan", False),
    ("127.0.0.1", "127.0.0.1", False), ("127.0.0.1:80x", "127.0.0.1", False),
])
def test_host_allowed(header, bound, allowed):
    """The Host rule on its own (server.host_allowed) for a server on port 8080: loopback
    names, the --host given and, for a wildcard --host, IP addresses but no DNS names."""
    assert server_module.host_allowed(header, bound, 8080) is allowed


# 9. Limits: connections, slow clients, table requests per client --------------------------------

def ok_request(server, timeout: float = 5.0) -> int:
    """The status of a normal request (the page's progress poll), given `timeout` seconds."""
    return request(server, "/api/progress", timeout=timeout)[0]


def test_200_connections_do_not_exhaust_the_server(server):
    """200 connections held open (idle, or with half a request): a normal request is still
    answered (each newcomer closes the connection that has waited longest), and the server
    never holds more than max_connections of them."""
    port = server.server_address[1]
    sockets = []
    try:
        for i in range(200):
            sock = socket.create_connection(("127.0.0.1", port), timeout=5)
            if i % 2:
                sock.sendall(b"GET /api/progress HTTP/1.1\r\nHost: 127.0.0.1\r\n")  # no end
            sockets.append(sock)
        assert ok_request(server) == 200
        wait_for(lambda: server.open_connections <= server.max_connections, seconds=10)
    finally:
        for sock in sockets:
            sock.close()
    wait_for(lambda: server.open_connections == 0, seconds=10)
    assert ok_request(server) == 200


def test_a_trickling_client_is_cut_off(server):
    """A client sending its request head a byte at a time is closed once request_timeout_s has
    passed (a per-read timeout alone would let it hold a thread forever); a normal request is
    answered meanwhile."""
    server.request_timeout_s = 1.0
    with socket.create_connection(("127.0.0.1", server.server_address[1]), timeout=5) as sock:
        sock.sendall(b"GET /api/progress HTTP/1.1\r\n")
        deadline = time.monotonic() + 15.0  # bounds the loop: the server cuts it after ~1 s
        closed = False
        while time.monotonic() < deadline and not closed:
            try:
                sock.sendall(b"X")
                time.sleep(0.1)
                sock.setblocking(False)
                closed = sock.recv(4096) == b""
            except BlockingIOError:
                pass
            except OSError:  # reset or broken pipe: closed too
                closed = True
            finally:
                sock.setblocking(True)
            if not closed:
                assert ok_request(server) == 200
    assert closed


@pytest.fixture
def blocked_sky(server):
    """/api/sky requests that wait for `release`; `waiting` counts those that have started."""
    release = threading.Event()
    waiting = []

    def sky_at(atmosphere, time_text, lat, lon):
        waiting.append(time_text)
        assert release.wait(30)
        return {"time_utc": time_text}

    server.sky_at = sky_at
    yield SimpleNamespace(release=release, waiting=waiting)
    release.set()


def test_busy_connections_give_a_quick_json_503(server, blocked_sky):
    """With every connection answering a request, a newcomer gets 503 with Retry-After at
    once (not a hung connection), and is served again once they are done."""
    server.max_connections = 3
    threads = [fetch_in_thread(server, BERLIN_NOON) for _ in range(3)]
    wait_for(lambda: len(blocked_sky.waiting) == 3)
    answer = request(server, "/api/progress", timeout=5)
    assert answer[0] == 503 and int(answer[1]["Retry-After"]) >= 1
    assert "try again" in json_error(answer)
    blocked_sky.release.set()
    for thread, result in threads:
        thread.join(30)
        assert result[0][0] == 200
    assert ok_request(server) == 200


def test_a_client_supersedes_only_its_own_table_requests(server, blocked_tables):
    """Table policy (table_service docstring): one computation at a time; a client's newer
    request cancels its own older one (409) but not another client's, which waits its turn."""
    def fetch(query: str, client: str):
        result = []
        thread = threading.Thread(target=lambda: result.append(request(
            server, f"/api/tables?{query}", headers={CLIENT_HEADER: client}, timeout=30)),
            daemon=True)
        thread.start()
        return thread, result

    a_old = fetch("albedo=0.1", "page-a")
    wait_for(lambda: len(blocked_tables.started) == 1)
    b = fetch("albedo=0.2", "page-b")
    wait_for(lambda: server.service._waiting == 2)
    a_new = fetch("albedo=0.3", "page-a")
    wait_for(lambda: server.service._waiting == 3)
    blocked_tables.release.set()
    for thread, _ in (a_old, b, a_new):
        thread.join(30)
    assert a_old[1][0][0] == 409
    assert b[1][0][0] == 200 and a_new[1][0][0] == 200
    assert sorted(r.albedo for r in blocked_tables.started) == [0.1, 0.2, 0.3]


# 10. Logs and errors ---------------------------------------------------------------------------

@pytest.fixture
def logged(server):
    """The server's log lines."""
    lines = []
    server.log = lines.append
    return lines


def test_a_client_leaving_mid_answer_logs_no_traceback(server, logged, capfd, monkeypatch):
    """A client that resets its connection while a 64 MiB answer is being written: no
    traceback on stderr, nothing but the request in the log, and the server goes on."""
    monkeypatch.setattr(TableService, "tables", lambda self, request, client="": bytes(64 << 20))
    for _ in range(3):
        sock = socket.create_connection(("127.0.0.1", server.server_address[1]), timeout=5)
        sock.sendall(b"GET /api/tables HTTP/1.1\r\n" + host(server) + b"\r\n")
        sock.recv(1024)  # the answer has started
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, b"\x01\x00\x00\x00\x00\x00\x00\x00")
        sock.close()  # linger 0: a reset
    wait_for(lambda: server.open_connections == 0, seconds=20)
    assert ok_request(server) == 200
    err = capfd.readouterr().err
    assert "Traceback" not in err and "Error" not in err
    assert not any("Error" in line or "error" in line for line in logged), logged


def test_control_characters_are_escaped_in_the_log(server, logged):
    raw_exchange(server, b"GET /\x1b[2J\x1b]0;owned\x07x\x7f\x9b HTTP/1.1\r\n" + host(server)
                 + b"Connection: close\r\n\r\n")
    text = "\n".join(logged)
    assert logged and "owned" in text
    assert not any(ord(c) < 0x20 or 0x7F <= ord(c) < 0xA0 for c in text), ascii(text)
    assert "\\x1b[2J" in text and "\\x07" in text and "\\x7f" in text and "\\x9b" in text


def test_an_internal_failure_is_a_json_500_and_one_log_line(server, logged, capfd):
    def sky_at(*args):
        raise RuntimeError("boom")

    server.sky_at = sky_at
    answer = request(server, BERLIN_NOON)
    assert answer[0] == 500
    assert "RuntimeError" in json_error(answer)
    assert [line for line in logged if "internal error" in line] == [
        line for line in logged if "boom" in line]
    assert len([line for line in logged if "boom" in line]) == 1
    assert "Traceback" not in capfd.readouterr().err
    assert ok_request(server) == 200


OUT_OF_RANGE_TIMES = ["0001-01-01T00:00%2B01:00", "9999-12-31T23:59-01:00",
                      "10000-01-01T00:00Z", "99999-01-01T00:00Z", "0000-01-01T00:00Z",
                      "-0001-01-01T00:00Z", "2024-13-01T00:00Z", "2024-02-30T00:00Z"]


@pytest.mark.parametrize("when", OUT_OF_RANGE_TIMES)
def test_sky_date_out_of_range_is_json_400(server, when):
    answer = request(server, f"/api/sky?time={when}&lat=52.5&lon=13.4")
    assert answer[0] == 400
    assert "time" in json_error(answer)


@pytest.mark.parametrize("when", ["0001-01-01T00:00Z", "9999-12-31T23:59Z"])
def test_sky_at_the_ends_of_the_calendar_is_answered(server, when):
    status, _, body = request(server, f"/api/sky?time={when}&lat=52.5&lon=13.4")
    assert status == 200
    assert json.loads(body)["time_utc"].startswith(when[:10])


def test_the_viewer_adds_a_bounded_amount_to_the_cache(server, tmp_path, monkeypatch):
    """Once a service has stored its VIEWER_CACHE_BYTES of new tables (here: a budget of one
    byte, crossed by the first entry), full tables of other parameters are still answered but
    no longer written; the cache's own size limit is the cache's (TableCache.max_bytes)."""
    monkeypatch.setattr(table_service, "QUALITIES", {"preview": (4, 0.25), "full": (4, 0.3)})
    cache = server.service.cache
    assert isinstance(cache, table_service.ViewerCache)
    assert cache.budget_bytes == table_service.VIEWER_CACHE_BYTES
    assert cache.max_bytes == TableCache(tmp_path / "other").max_bytes
    cache.budget_bytes = 1
    status, _, first = request(server, "/api/tables?quality=full&albedo=0.1")
    assert status == 200 and first[:4] == b"SKYT"
    stored = table_entries(tmp_path / "cache")
    assert len(stored) == 1 and cache.stored_bytes == sum(size for size, _ in stored.values())
    status, _, second = request(server, "/api/tables?quality=full&albedo=0.2")
    assert status == 200 and second[:4] == b"SKYT" and second != first
    assert table_entries(tmp_path / "cache") == stored


def test_fast_description_route(server):
    """/api/fast: the fast model's description of an atmosphere, answered without the table
    lock; unknown atmospheres and parameters are a JSON 400 naming them, no token a 403."""
    from skyscatter.viewer.gpu_fast import decode_fast
    status, headers, body = request(server, "/api/fast?atmosphere=earth")
    assert status == 200 and headers["Content-Type"] == "application/octet-stream"
    header, arrays = decode_fast(body)
    assert header["names"] == ["air", "ozone", "aerosol"] and header["altitudes"] == 2001
    status, _, body = request(server, "/api/fast?atmosphere=venus-of-nowhere")
    assert status == 400 and "venus-of-nowhere" in json.loads(body)["error"]
    status, _, body = request(server, "/api/fast?atmosphere=earth&amount_air=2")
    assert status == 400 and "amount_air" in json.loads(body)["error"]
    status, _, _ = request(server, "/api/fast?atmosphere=earth", headers={TOKEN_HEADER: "x"})
    assert status == 403
