"""The viewer's web server: the page's own static files and a small JSON/binary API, on
loopback unless asked otherwise, answering only the person who started it.

Routes (GET and HEAD only; anything else 405):
  /                     the page (static/index.html)
  /static/PATH          a file of the static directory, looked up in the list made at start-up:
                        a request never becomes a file-system path, so `..`, encoded slashes
                        or links cannot reach outside it (404)
  /api/atmospheres      what can be shown (`TableService.describe`, with the clouds offered:
                        `CloudService.describe` under "clouds")
  /api/tables?...       the tables of one atmosphere, binary (`gpu_tables.encode`); 400 for a
                        bad parameter, 409 when a newer request of the same client superseded
                        it, 429 when too many wait
  /api/progress         the table computation under way
  /api/fast?atmosphere  the compact description of an atmosphere for the page's fast model
                        (Hillaire 2020 on the GPU), binary (`gpu_fast.encode_fast`)
  /api/clouds?clouds&atmosphere
                        cloud layers offered by name (a preset or the --clouds file), binary
                        (`gpu_clouds.encode_clouds`); 400 for a name not offered
  /api/sky?atmosphere&time&lat&lon
                        the sun's zenith and azimuth [deg] at that place and time and the
                        stars above the horizon (directions, XYZ irradiance above the air)

Who may ask (checked in this order, before anything is computed):
  Host     the address the server was started on with its port: 127.0.0.1, localhost or
           [::1], the --host given, and for a wildcard --host (0.0.0.0, ::) any IP address or
           this computer's name (421 otherwise). A page of another site that rebinds its DNS
           name to 127.0.0.1 sends its own name as Host and is refused.
  Origin   absent (same-origin GETs, address bar) or the server's own origin (403 otherwise).
  token    every /api/ request carries the per-launch secret of the printed address
           (`?token=...`, which the page sends as the X-Skyscatter-Token header; 403 without it,
           compared with hmac.compare_digest); the page and its static files need none.

Limits: request lines over MAX_URL bytes get 414, requests with a body 413, more than
MAX_FIELDS query fields or a repeated field 400. At most `max_connections` connections are
served at once: a new one closes the one that has waited longest for its next request, and
gets 503 when every connection is busy answering. A request's line and headers must arrive
within `request_timeout_s` of the connection's last answer (an idle or trickling client is cut
off); each read and each whole response write has SOCKET_TIMEOUT_S. The listen backlog
(LISTEN_BACKLOG) takes bursts of connects without the kernel's retry stalls. Table requests:
one computation at a time (`TableService`). Every error is a JSON {"error": message} that the
page shows, a failure of our own a 500 with one log line; a client that goes away mid-answer
is not logged; control characters of a request are escaped in the log. The server keeps
running.
"""

from __future__ import annotations

import contextlib
import hmac
import ipaddress
import json
import mimetypes
import secrets
import socket
import sys
import threading
import time
import webbrowser
from collections.abc import Callable
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from urllib.parse import parse_qsl, quote, urlsplit

from skyscatter.atmosphere.model import Atmosphere
from skyscatter.errors import InputError, SkyscatterError
from skyscatter.viewer.cloud_service import CloudService
from skyscatter.viewer.table_service import BusyError, SupersededError, TableService

__all__ = ["CLIENT_HEADER", "LISTEN_BACKLOG", "MAX_CONNECTIONS", "REQUEST_TIMEOUT_S",
           "SOCKET_TIMEOUT_S", "STATIC_DIR", "SkyAt", "TOKEN_HEADER", "ViewerServer",
           "host_allowed", "make_server", "printable", "serve_forever", "static_files"]

# (atmosphere, ISO time, latitude [deg], longitude [deg]) -> the JSON answer of /api/sky:
# {sun_zenith_deg, sun_azimuth_deg, time_utc, stars: {count, directions_enu, irradiance_xyz}};
# given by the caller (`api.viewer_server`), which owns the ephemeris; InputError for a bad
# time or place
SkyAt = Callable[[Atmosphere, str, float, float], dict]

STATIC_DIR = Path(__file__).parent / "static"
MAX_URL = 4096  # bytes of the request line
MAX_FIELDS = 40  # query fields
MAX_CONNECTIONS = 32  # served at once: a page uses up to 6, a dome a few pages
REQUEST_TIMEOUT_S = 10.0  # for a request's line and headers, from the connection's last answer
SOCKET_TIMEOUT_S = 30.0  # each read; each whole response write (sendall): 23 MiB of tables
LISTEN_BACKLOG = 256  # connects the kernel queues (Linux caps it at net.core.somaxconn)
TOKEN_HEADER = "X-Skyscatter-Token"  # the per-launch secret, as the page sends it
CLIENT_HEADER = "X-Skyscatter-Client"  # a page's own id: its table requests supersede each other
LOOPBACK_NAMES = frozenset({"127.0.0.1", "localhost", "::1"})
_TYPES = {".js": "text/javascript", ".glsl": "text/plain", ".frag": "text/plain",
          ".json": "application/json", ".css": "text/css", ".html": "text/html"}
_DISCONNECTS = (ConnectionError, TimeoutError)  # the client went away or stalled
_ESCAPES = {code: f"\\x{code:02x}" for code in (*range(0x20), *range(0x7F, 0xA0))}


def printable(text: str) -> str:
    """`text` with its control characters (C0, DEL, C1) written as \\xNN, for a log line."""
    return text.translate(_ESCAPES)


def static_files(root: Path = STATIC_DIR) -> dict[str, Path]:
    """URL path below /static/ -> file, for every regular file under `root` (not following
    links out of it)."""
    root = root.resolve()
    files = {}
    for path in root.rglob("*"):
        if path.is_file() and not path.is_symlink() and path.resolve().is_relative_to(root):
            files[path.relative_to(root).as_posix()] = path
    return files


def host_allowed(header: str, bound_host: str, port: int) -> bool:
    """Whether a request's Host header names this server: one of LOOPBACK_NAMES, the host it
    was bound to (`bound_host`, as given to --host) or, bound to a wildcard address (0.0.0.0,
    ::), any IP address or this computer's name; with `port` (omitted only for port 80)."""
    try:
        parts = urlsplit(f"//{header.strip()}")
        name, given_port = parts.hostname, parts.port
    except ValueError:
        return False
    if not name or parts.username is not None or parts.password is not None \
            or parts.path or parts.query or parts.fragment or (given_port or 80) != port:
        return False
    bound = bound_host.strip("[]").lower()
    if name in LOOPBACK_NAMES or name == bound:
        return True
    if bound in ("", "0.0.0.0", "::"):  # a rebinding page sends a DNS name, never an address
        try:
            ipaddress.ip_address(name)
            return True
        except ValueError:
            return name == socket.gethostname().lower()
    return False


class _RefusedError(Exception):
    """A request answered with an error before it is served: HTTP status, message, headers."""

    def __init__(self, status: int, message: str, headers: dict | None = None) -> None:
        super().__init__(message)
        self.status, self.headers = status, headers


class ViewerServer(ThreadingHTTPServer):
    """A threading HTTP server holding the TableService, the static file list, the launch's
    token and its connections (module docstring: who may ask, limits).

    `max_connections` and `request_timeout_s` start at MAX_CONNECTIONS and REQUEST_TIMEOUT_S;
    a connection is tracked from accept to close with the monotonic time by which its next
    request head must have arrived (None while a request is answered)."""

    daemon_threads = True
    request_queue_size = LISTEN_BACKLOG

    def __init__(self, address: tuple[str, int], service: TableService, sky_at: SkyAt,
                 log: Callable[[str], None] | None = None) -> None:
        self.service = service
        self.clouds = CloudService(service)  # `offer` adds a --clouds file
        self.sky_at = sky_at
        self.files = static_files()
        self.log = log
        self.token = secrets.token_urlsafe(32)
        self.max_connections = MAX_CONNECTIONS
        self.request_timeout_s = REQUEST_TIMEOUT_S
        self._deadlines: dict[socket.socket, float | None] = {}
        self._connections = threading.Lock()
        super().__init__(address, Handler)

    @property
    def url(self) -> str:
        """The page's address with the launch's token: what to open (and only what to share
        with someone who may use this viewer)."""
        host, port = self.server_address[:2]
        host = f"[{host}]" if ":" in host else host
        return f"http://{host}:{port}/?token={quote(self.token)}"

    @property
    def open_connections(self) -> int:
        """Connections accepted and not yet closed."""
        with self._connections:
            return len(self._deadlines)

    def host_allowed(self, header: str) -> bool:
        """`host_allowed` for this server's address."""
        return host_allowed(header, self.bound_host, self.server_address[1])

    def server_bind(self) -> None:
        self.bound_host = self.server_address[0]  # as given, before the socket resolves it
        super().server_bind()

    def report(self, message: str) -> None:
        """One line into the log (stderr without one), its control characters escaped."""
        line = printable(message)
        if self.log is not None:
            self.log(line)
        else:
            print(f"skyscatter viewer: {line}", file=sys.stderr, flush=True)

    # Connections: a cap, deadlines for request heads ----------------------------------------

    def process_request(self, request: socket.socket, client_address: tuple) -> None:
        with self._connections:
            admitted = len(self._deadlines) < self.max_connections or self._close_idle()
            if admitted:
                self._deadlines[request] = time.monotonic() + self.request_timeout_s
        if not admitted:
            self._refuse_full(request)
            self.shutdown_request(request)
            return
        super().process_request(request, client_address)

    def shutdown_request(self, request: socket.socket) -> None:
        with self._connections:
            self._deadlines.pop(request, None)
        super().shutdown_request(request)

    def awaiting_request(self, connection: socket.socket, waiting: bool) -> None:
        """Mark `connection` as waiting for its next request head (from now, with a deadline)
        or as being answered (no deadline, not closed for a newcomer)."""
        with self._connections:
            if connection in self._deadlines:
                self._deadlines[connection] = (time.monotonic() + self.request_timeout_s
                                               if waiting else None)

    def service_actions(self) -> None:
        """Cut off the connections whose request head is late (serve_forever calls this
        every poll interval)."""
        now = time.monotonic()
        with self._connections:
            for connection, deadline in list(self._deadlines.items()):
                if deadline is not None and deadline < now:
                    self._cut(connection)

    def _close_idle(self) -> bool:
        """Close the connection that has waited longest for a request; False if none waits
        (call with the lock held)."""
        waiting = [(deadline, id(c), c) for c, deadline in self._deadlines.items()
                   if deadline is not None]
        if not waiting:
            return False
        self._cut(min(waiting)[2])
        return True

    def _cut(self, connection: socket.socket) -> None:
        """Stop tracking `connection` and shut it down: its thread's read returns at once
        (call with the lock held; the thread closes it)."""
        del self._deadlines[connection]
        with contextlib.suppress(OSError):
            connection.shutdown(socket.SHUT_RDWR)

    def _refuse_full(self, connection: socket.socket) -> None:
        """A 503 written without blocking the accepting thread."""
        body = json.dumps({"error": f"the viewer is answering {self.max_connections} "
                                    "requests already; try again in a second"}).encode()
        head = ("HTTP/1.1 503 Service Unavailable\r\nContent-Type: application/json\r\n"
                f"Content-Length: {len(body)}\r\nRetry-After: 1\r\nCache-Control: no-store\r\n"
                "Connection: close\r\n\r\n").encode()
        with contextlib.suppress(OSError):
            connection.setblocking(False)
            connection.send(head + body)

    def handle_error(self, request: socket.socket, client_address: tuple) -> None:
        """A client that went away is no error; anything else is one log line."""
        error = sys.exc_info()[1]
        if not isinstance(error, _DISCONNECTS):
            self.report(f"{client_address[0]}: internal error: {type(error).__name__}: {error}")


def make_server(service: TableService, sky_at: SkyAt, host: str = "127.0.0.1", port: int = 0,
                log: Callable[[str], None] | None = None) -> ViewerServer:
    """A ViewerServer bound to (host, port) (port 0: a free one); InputError when the port
    cannot be had."""
    if not (isinstance(port, int) and 0 <= port <= 65535):
        raise InputError(f"--port {port!r} must be an integer in [0, 65535] (0: any free port)",
                         key="port", value=port)
    try:
        return ViewerServer((host, port), service, sky_at, log)
    except OSError as error:
        raise InputError(f"cannot listen on {host}:{port}: {error.strerror}; pick another "
                         "--port (or 0 for any free one)", key="port", value=port) from None


def serve_forever(server: ViewerServer, open_browser: bool) -> None:
    """Serve until interrupted; open the page in the default browser first if asked."""
    if open_browser:
        threading.Timer(0.3, webbrowser.open, args=(server.url,)).start()
    try:
        server.serve_forever()
    finally:
        server.server_close()


class Handler(BaseHTTPRequestHandler):
    """Answers one request (module docstring)."""

    server: ViewerServer
    server_version = "skyscatter-viewer"
    protocol_version = "HTTP/1.1"
    timeout = SOCKET_TIMEOUT_S

    def log_message(self, format: str, *args) -> None:  # noqa: A002 (the base class's name)
        if self.server.log is not None:
            self.server.report(f"{self.address_string()} {format % args}")

    def handle_one_request(self) -> None:
        self.server.awaiting_request(self.connection, True)
        super().handle_one_request()

    def parse_request(self) -> bool:
        if len(self.raw_requestline) > MAX_URL:
            self.send_error(HTTPStatus.REQUEST_URI_TOO_LONG,
                            f"request line longer than {MAX_URL} bytes")
            return False
        if not super().parse_request():
            return False
        self.server.awaiting_request(self.connection, False)
        return True

    def send_error(self, code: int, message: str | None = None,
                   explain: str | None = None) -> None:
        """http.server's own errors (malformed request lines, too many headers, unknown
        methods) as JSON too, and the connection closed."""
        self.close_connection = True
        if not getattr(self, "request_version", None) or not getattr(self, "command", None):
            self.request_version, self.command = "HTTP/1.1", "GET"
        if not hasattr(self, "requestline"):  # refused before the request line was parsed
            self.requestline = ""
        self._error(code, message or HTTPStatus(code).phrase)

    def _send(self, status: int, body: bytes, content_type: str, extra: dict | None = None) -> None:
        self.send_response(status)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        for key, value in (extra or {}).items():
            self.send_header(key, value)
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)

    def _json(self, status: int, value: object) -> None:
        self._send(status, json.dumps(value).encode(), "application/json")

    def _error(self, status: int, message: str, extra: dict | None = None) -> None:
        self._send(status, json.dumps({"error": message}).encode(), "application/json", extra)

    def _check_caller(self) -> None:
        """Refuse a request for another host name (DNS rebinding) or from another origin."""
        hosts = self.headers.get_all("Host", [])
        host = hosts[0] if len(hosts) == 1 else ", ".join(hosts)
        if len(hosts) != 1 or not self.server.host_allowed(host):
            self.close_connection = True
            raise _RefusedError(HTTPStatus.MISDIRECTED_REQUEST,
                                f"this viewer does not answer for host {host!r}; open the address "
                                "that `skyscatter view` printed")
        origin = self.headers.get("Origin")
        if origin is not None and origin.strip().lower() != f"http://{host.strip().lower()}":
            self.close_connection = True
            raise _RefusedError(HTTPStatus.FORBIDDEN,
                                f"requests from {origin!r} are refused; the viewer answers only "
                                "its own page")

    def _check_token(self, query: dict[str, str]) -> None:
        in_query = query.pop("token", "")
        given = self.headers.get(TOKEN_HEADER) or in_query
        if not hmac.compare_digest(given.encode("utf-8", "replace"), self.server.token.encode()):
            raise _RefusedError(HTTPStatus.FORBIDDEN,
                                "missing or wrong token: open the address that `skyscatter view` "
                                "printed (it ends in ?token=...)")

    def _refuse_method(self) -> None:
        self.close_connection = True  # its body is not read: it must not become a request
        try:
            self._check_caller()
        except _RefusedError as refused:
            self._error(refused.status, str(refused))
            return
        self._error(HTTPStatus.METHOD_NOT_ALLOWED,
                    f"{self.command} is not allowed; the viewer only answers GET",
                    {"Allow": "GET, HEAD"})

    do_POST = do_PUT = do_DELETE = do_PATCH = do_OPTIONS = _refuse_method  # noqa: N815

    def do_HEAD(self) -> None:
        self.do_GET()

    def do_GET(self) -> None:
        try:
            self._answer()
        except _RefusedError as refused:
            self._error(refused.status, str(refused), refused.headers)
        except SkyscatterError as error:  # InputError, ConfigError: the request's fault
            self._error(HTTPStatus.BAD_REQUEST, str(error))
        except SupersededError as error:
            self._error(HTTPStatus.CONFLICT, str(error))
        except BusyError as error:
            self._error(HTTPStatus.TOO_MANY_REQUESTS, str(error), {"Retry-After": "1"})
        except _DISCONNECTS:
            self.close_connection = True
        except Exception as error:  # a failure of ours: one log line and a JSON 500
            self.server.report(f"internal error answering {self.requestline!r}: "
                               f"{type(error).__name__}: {error}")
            self.close_connection = True
            self._error(HTTPStatus.INTERNAL_SERVER_ERROR,
                        f"internal error ({type(error).__name__}); the server log has details")

    def _answer(self) -> None:
        self._check_caller()
        length = self.headers.get("Content-Length", "0")
        if length.strip() not in ("", "0") or self.headers.get("Transfer-Encoding"):
            self.close_connection = True
            raise _RefusedError(HTTPStatus.REQUEST_ENTITY_TOO_LARGE,
                                "the viewer takes no request body")
        parts = urlsplit(self.path)
        try:
            fields = parse_qsl(parts.query, keep_blank_values=True, max_num_fields=MAX_FIELDS)
        except ValueError:
            raise _RefusedError(HTTPStatus.BAD_REQUEST,
                                f"more than {MAX_FIELDS} query parameters") from None
        query = dict(fields)
        if len(query) != len(fields):
            twice = sorted({key for key, _ in fields if sum(k == key for k, _ in fields) > 1})
            raise _RefusedError(HTTPStatus.BAD_REQUEST,
                                f"query parameter {twice[0]!r} is given twice")
        route = parts.path
        if route in ("/", "/index.html"):
            self._static("index.html")
        elif route.startswith("/static/"):
            self._static(route[len("/static/"):])
        elif not route.startswith("/api/"):
            raise _RefusedError(HTTPStatus.NOT_FOUND, f"no such page: {route}")
        else:
            self._check_token(query)
            self._api(route, query)

    def _api(self, route: str, query: dict[str, str]) -> None:
        service = self.server.service
        if route == "/api/atmospheres":
            self._json(HTTPStatus.OK, dict(service.describe(),
                                           clouds=self.server.clouds.describe()))
        elif route == "/api/clouds":
            clouds = self.server.clouds
            self._send(HTTPStatus.OK, clouds.message(*clouds.parse(query)),
                       "application/octet-stream")
        elif route == "/api/tables":
            client = self.headers.get(CLIENT_HEADER) or self.client_address[0]
            message = service.tables(service.parse(query), client=client[:64])
            self._send(HTTPStatus.OK, message, "application/octet-stream")
        elif route == "/api/progress":
            self._json(HTTPStatus.OK, service.progress)
        elif route == "/api/fast":
            unknown = sorted(set(query) - {"atmosphere"})
            if unknown:
                raise InputError(f"unknown parameter {unknown[0]!r}; known: atmosphere",
                                 key=unknown[0])
            self._send(HTTPStatus.OK,
                       service.fast_message(query.get("atmosphere", service.default)),
                       "application/octet-stream")
        elif route == "/api/sky":
            self._json(HTTPStatus.OK, self._sky(query))
        else:
            raise _RefusedError(HTTPStatus.NOT_FOUND, f"no such page: {route}")

    def _static(self, name: str) -> None:
        path = self.server.files.get(name)
        if path is None:
            raise _RefusedError(HTTPStatus.NOT_FOUND, f"no such file: /static/{name}")
        content_type = _TYPES.get(path.suffix) or mimetypes.guess_type(path.name)[0] \
            or "application/octet-stream"
        if content_type.startswith("text/") or content_type == "application/json":
            content_type += "; charset=utf-8"
        self._send(HTTPStatus.OK, path.read_bytes(), content_type)

    def _sky(self, query: dict[str, str]) -> dict:
        unknown = set(query) - {"atmosphere", "time", "lat", "lon"}
        if unknown:
            raise InputError(f"unknown parameter {sorted(unknown)[0]!r}; known: atmosphere, "
                             "time, lat, lon", key=sorted(unknown)[0])
        for key in ("time", "lat", "lon"):
            if key not in query:
                raise InputError(f"missing parameter {key!r}", key=key)
        service = self.server.service
        atmosphere = service.atmosphere(query.get("atmosphere", service.default))
        try:
            lat, lon = float(query["lat"]), float(query["lon"])
        except ValueError:
            raise InputError(f"lat = {query['lat']!r} and lon = {query['lon']!r} must be "
                             "numbers [deg]", key="lat") from None
        return self.server.sky_at(atmosphere, query["time"], lat, lon)
