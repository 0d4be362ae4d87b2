"""The viewer's web server: the page's own static files and a small JSON/binary API, on
loopback unless asked otherwise.

Routes (GET and HEAD only; anything else 405):
  /                     the page (static/index.html)
  /static/PATH          a file of the static directory, looked up in the list made at start-up:
                        a request never becomes a file-system path, so `..`, encoded slashes
                        or links cannot reach outside it (404)
  /api/atmospheres      what can be shown (`TableService.describe`)
  /api/tables?...       the tables of one atmosphere, binary (`gpu_tables.encode`); 400 for a
                        bad parameter, 409 when a newer request superseded it, 429 when too
                        many wait
  /api/progress         the table computation under way
  /api/sky?atmosphere&time&lat&lon
                        the sun's zenith and azimuth [deg] at that place and time and the
                        stars above the horizon (directions, XYZ irradiance above the air)

Limits: request lines over MAX_URL bytes get 414, requests with a body 413, more than
MAX_FIELDS query fields or a repeated field 400. Every error is a JSON {"error": message}
that the page shows; the server keeps running.
"""

from __future__ import annotations

import json
import mimetypes
import threading
import webbrowser
from collections.abc import Callable
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from urllib.parse import parse_qsl, urlsplit

from skyscatter.atmosphere.model import Atmosphere
from skyscatter.errors import InputError, SkyscatterError
from skyscatter.viewer.table_service import BusyError, SupersededError, TableService

__all__ = ["STATIC_DIR", "SkyAt", "ViewerServer", "make_server", "serve_forever",
           "static_files"]

# (atmosphere, ISO time, latitude [deg], longitude [deg]) -> the JSON answer of /api/sky:
# {sun_zenith_deg, sun_azimuth_deg, time_utc, stars: {count, directions_enu, irradiance_xyz}};
# given by the caller (`api.viewer_server`), which owns the ephemeris; InputError for a bad
# time or place
SkyAt = Callable[[Atmosphere, str, float, float], dict]

STATIC_DIR = Path(__file__).parent / "static"
MAX_URL = 4096  # bytes of the request line
MAX_FIELDS = 40  # query fields
_TYPES = {".js": "text/javascript", ".glsl": "text/plain", ".frag": "text/plain",
          ".json": "application/json", ".css": "text/css", ".html": "text/html"}


def static_files(root: Path = STATIC_DIR) -> dict[str, Path]:
    """URL path below /static/ -> file, for every regular file under `root` (not following
    links out of it)."""
    root = root.resolve()
    files = {}
    for path in root.rglob("*"):
        if path.is_file() and not path.is_symlink() and path.resolve().is_relative_to(root):
            files[path.relative_to(root).as_posix()] = path
    return files


class ViewerServer(ThreadingHTTPServer):
    """A threading HTTP server holding the TableService and the static file list."""

    daemon_threads = True

    def __init__(self, address: tuple[str, int], service: TableService, sky_at: SkyAt,
                 log: Callable[[str], None] | None = None) -> None:
        self.service = service
        self.sky_at = sky_at
        self.files = static_files()
        self.log = log
        super().__init__(address, Handler)

    @property
    def url(self) -> str:
        host, port = self.server_address[:2]
        host = f"[{host}]" if ":" in host else host
        return f"http://{host}:{port}/"


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
    timeout = 30  # seconds a client may take to send its request (slow clients hold a thread)

    def log_message(self, format: str, *args) -> None:  # noqa: A002 (the base class's name)
        if self.server.log is not None:
            self.server.log(f"{self.address_string()} {format % args}")

    def parse_request(self) -> bool:
        if len(self.raw_requestline) > MAX_URL:
            self.send_error(HTTPStatus.REQUEST_URI_TOO_LONG,
                            f"request line longer than {MAX_URL} bytes")
            return False
        return super().parse_request()

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

    def _refuse_method(self) -> None:
        self.close_connection = True  # its body is not read: it must not become a request
        self._error(HTTPStatus.METHOD_NOT_ALLOWED,
                    f"{self.command} is not allowed; the viewer only answers GET",
                    {"Allow": "GET, HEAD"})

    do_POST = do_PUT = do_DELETE = do_PATCH = do_OPTIONS = _refuse_method  # noqa: N815

    def do_HEAD(self) -> None:
        self.do_GET()

    def do_GET(self) -> None:
        length = self.headers.get("Content-Length", "0")
        if length.strip() not in ("", "0") or self.headers.get("Transfer-Encoding"):
            self.close_connection = True
            self._error(HTTPStatus.REQUEST_ENTITY_TOO_LARGE, "the viewer takes no request body")
            return
        parts = urlsplit(self.path)
        try:
            fields = parse_qsl(parts.query, keep_blank_values=True, max_num_fields=MAX_FIELDS)
        except ValueError:
            self._error(HTTPStatus.BAD_REQUEST, f"more than {MAX_FIELDS} query parameters")
            return
        query = dict(fields)
        if len(query) != len(fields):
            twice = sorted({key for key, _ in fields if sum(k == key for k, _ in fields) > 1})
            self._error(HTTPStatus.BAD_REQUEST, f"query parameter {twice[0]!r} is given twice")
            return
        route = parts.path
        try:
            if route in ("/", "/index.html"):
                self._static("index.html")
            elif route.startswith("/static/"):
                self._static(route[len("/static/"):])
            elif route == "/api/atmospheres":
                self._json(HTTPStatus.OK, self.server.service.describe())
            elif route == "/api/tables":
                service = self.server.service
                message = service.tables(service.parse(query))
                self._send(HTTPStatus.OK, message, "application/octet-stream")
            elif route == "/api/progress":
                self._json(HTTPStatus.OK, self.server.service.progress)
            elif route == "/api/sky":
                self._json(HTTPStatus.OK, self._sky(query))
            else:
                self._error(HTTPStatus.NOT_FOUND, f"no such page: {route}")
        except (InputError, SkyscatterError) as error:
            self._error(HTTPStatus.BAD_REQUEST, str(error))
        except SupersededError as error:
            self._error(HTTPStatus.CONFLICT, str(error))
        except BusyError as error:
            self._error(HTTPStatus.TOO_MANY_REQUESTS, str(error), {"Retry-After": "1"})

    def _static(self, name: str) -> None:
        path = self.server.files.get(name)
        if path is None:
            self._error(HTTPStatus.NOT_FOUND, f"no such file: /static/{name}")
            return
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
