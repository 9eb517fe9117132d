"""The Starlette application: the gateway's read-only routes over one ServedRecording.

Routes, ``at`` moments (query or ``/at/{seconds}`` base), 404/405 as GenericError, CORS and bounds
live here; the bodies come from ``faults_json``, ``discovery_json`` and ``stream``.
"""

from __future__ import annotations

import json
import math
from typing import TYPE_CHECKING, Any

from starlette.applications import Starlette
from starlette.exceptions import HTTPException
from starlette.middleware import Middleware
from starlette.middleware.cors import CORSMiddleware
from starlette.responses import FileResponse, Response
from starlette.routing import Route

from medkit_replay.gateway import discovery_json
from medkit_replay.gateway.errors import (
    GatewayError,
    error_body,
    invalid_parameter,
    method_not_allowed,
    not_found,
    unknown_route,
)
from medkit_replay.gateway.faults_json import (
    bulk_categories_body,
    entity_fault_list_body,
    fault_detail_body,
    fault_list_body,
    parse_status_filter,
    rosbag_descriptors_body,
)
from medkit_replay.gateway.stream import EventStream

if TYPE_CHECKING:
    from collections.abc import Awaitable, Callable, Sequence

    from starlette.requests import Request
    from starlette.types import ASGIApp, Receive, Scope, Send

    from medkit_replay.gateway.entities import Entity
    from medkit_replay.gateway.recording import ServedRecording

API = "/api/v1"
KINDS = ("areas", "components", "apps", "functions")
READ_METHODS = frozenset({"GET", "HEAD"})
ALL_METHODS = ["GET", "HEAD", "POST", "PUT", "PATCH", "DELETE"]
MAX_RESPONSE_BYTES = 256 * 1024 * 1024
"""The largest JSON body answered (a fault list of this size means something is wrong)."""
MAX_REQUEST_BYTES = 64 * 1024
"""The largest request (line, headers, body) the server reads; every route is a GET."""
MOMENT_PREFIX = "/at/"
ROSBAG_CATEGORY = "rosbags"
_TRUE = frozenset({"true", "1"})


class MomentPrefix:
    """``/at/{seconds}/api/v1/...`` is ``/api/v1/...`` at that moment: for clients that only
    take a server address (the web UI). The moment is kept in the scope for the routes."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        path = scope.get("path", "")
        if scope["type"] == "http" and path.startswith(MOMENT_PREFIX):
            text, _, rest = path[len(MOMENT_PREFIX) :].partition("/")
            try:
                seconds = _seconds(text)
            except GatewayError as err:
                await _json(err.status, error_body(err))(scope, receive, send)
                return
            scope = dict(scope)
            scope["path"] = "/" + rest
            scope["medkit_at"] = seconds
        await self.app(scope, receive, send)


def _seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise invalid_parameter("at", text, "a number of seconds from the recording's start")
    return value


def _json(status: int, body: object, headers: dict[str, str] | None = None) -> Response:
    text = json.dumps(body, ensure_ascii=False, separators=(",", ":"))
    if len(text) > MAX_RESPONSE_BYTES:  # characters: a lower bound of the bytes
        err = GatewayError(
            500, "x-medkit-response-too-large", "The answer exceeds the server's response bound"
        )
        text = json.dumps(error_body(err))
        status = err.status
    return Response(text, status, headers=headers, media_type="application/json")


class GatewayApp:
    """The routes' handlers over one recording (one instance per server)."""

    def __init__(self, served: ServedRecording, *, speed: float, max_streams: int = 2) -> None:
        self.served = served
        self.stream = EventStream(served, speed=speed, max_clients=max_streams)

    # -- helpers ---------------------------------------------------------------------------

    def moment(self, request: Request) -> int:
        """Bag time the request asks about: ``?at=``, else the ``/at/`` prefix, else ``--at``."""
        text = request.query_params.get("at")
        if text is not None:
            return self.served.moment(_seconds(text))
        prefixed = request.scope.get("medkit_at")
        return self.served.moment(prefixed if isinstance(prefixed, float) else None)

    def entity(self, request: Request) -> Entity:
        kind, entity_id = request.path_params["kind"], request.path_params["entity_id"]
        if kind not in KINDS:
            raise unknown_route(request.url.path)
        found = self.served.entities.get(kind, entity_id)
        if found is None:
            raise not_found(kind, entity_id)
        return found

    # -- root, health, the recording -------------------------------------------------------

    async def root(self, request: Request) -> Response:
        return _json(200, discovery_json.root_body())

    async def version_info(self, request: Request) -> Response:
        return _json(200, discovery_json.version_body())

    async def health(self, request: Request) -> Response:
        return _json(200, discovery_json.health_body(self.served.entities, self.served.end_ns))

    async def recording(self, request: Request) -> Response:
        return _json(200, self.served.recording_facts())

    # -- discovery -------------------------------------------------------------------------

    async def collection(self, request: Request) -> Response:
        kind = request.path_params["kind"]
        if kind not in KINDS:
            raise unknown_route(request.url.path)
        return _json(200, discovery_json.collection_body(self.served.entities, kind))

    async def detail(self, request: Request) -> Response:
        entity = self.entity(request)
        return _json(200, discovery_json.entity_body(self.served.entities, entity))

    async def related(self, request: Request) -> Response:
        entity = self.entity(request)
        name = request.path_params["relation"]
        body = discovery_json.relation_body(self.served.entities, entity, name)
        if body is None:
            raise unknown_route(request.url.path)
        return _json(200, body)

    # -- faults ----------------------------------------------------------------------------

    async def faults(self, request: Request) -> Response:
        query = request.query_params
        status = parse_status_filter(query.get("status"))
        t_ns = self.moment(request)
        history = self.served.history
        body = fault_list_body(
            history.faults_at(t_ns),
            history.correlation_at(t_ns),
            status,
            include_muted=query.get("include_muted", "").lower() in _TRUE,
            include_clusters=query.get("include_clusters", "").lower() in _TRUE,
            correlation_enabled=self.served.correlation_enabled,
        )
        return _json(200, body)

    async def entity_faults(self, request: Request) -> Response:
        entity = self.entity(request)
        status = parse_status_filter(
            request.query_params.get("status"), {_ID_FIELDS[entity.kind]: entity.id}
        )
        t_ns = self.moment(request)
        sources = self.served.entities.fault_sources(entity)
        return _json(
            200, entity_fault_list_body(self.served.history.faults_at(t_ns), sources, status)
        )

    async def fault(self, request: Request) -> Response:
        entity = self.entity(request)
        code = request.path_params["code"]
        t_ns = self.moment(request)
        found = self.served.history.fault_at(code, t_ns)
        if found is None:
            raise not_found("faults", code)
        body = fault_detail_body(
            found,
            self.served.captures_at(code, t_ns),
            [r for r in self.served.recordings_at(t_ns) if code in r.fault_codes],
            entity_kind=entity.kind,
            entity_id=entity.id,
        )
        return _json(200, body)

    # -- bulk data -------------------------------------------------------------------------

    async def bulk_categories(self, request: Request) -> Response:
        self.entity(request)
        return _json(200, bulk_categories_body())

    async def bulk_descriptors(self, request: Request) -> Response:
        entity = self.entity(request)
        category = request.path_params["category"]
        if category != ROSBAG_CATEGORY:
            raise not_found("bulk-data category", category)
        recordings = self._recordings_of(entity, self.moment(request))
        return _json(200, rosbag_descriptors_body(recordings, entity.kind, entity.id))

    async def bulk_download(self, request: Request) -> Response:
        entity = self.entity(request)
        category, file_id = request.path_params["category"], request.path_params["file_id"]
        if category != ROSBAG_CATEGORY:
            raise not_found("bulk-data category", category)
        held = {r.recording_id for r in self._recordings_of(entity, self.moment(request))}
        # Only a clip this replay wrote: the id is looked up, never joined to a path.
        path = self.served.clips.get(file_id) if file_id in held else None
        if path is None:
            raise not_found("bulk-data", file_id)
        return FileResponse(
            path,
            media_type=_MIMETYPES.get(path.suffix, "application/octet-stream"),
            filename=f"{file_id}{_EXTENSIONS.get(path.suffix, path.suffix)}",
        )

    def _recordings_of(self, entity: Entity, t_ns: int) -> list[Any]:
        codes = {
            f.fault_code
            for f in self.served.history.faults_at(t_ns)
            if self.served.entities.fault_sources(entity) & set(f.reporting_sources)
        }
        return [
            r
            for r in self.served.recordings_at(t_ns)
            if r.fault_codes and r.fault_codes[0] in codes
        ]

    # -- the event stream ------------------------------------------------------------------

    async def fault_stream(self, request: Request) -> Response:
        text = request.query_params.get("at")
        prefixed = request.scope.get("medkit_at")
        start = _seconds(text) if text is not None else prefixed
        return self.stream.response(
            request.headers.get("last-event-id"),
            self.served.moment(start) if isinstance(start, float) else None,
        )


_ID_FIELDS = {"areas": "area_id", "components": "component_id", "apps": "app_id",
              "functions": "function_id"}  # fmt: skip
_MIMETYPES = {".mcap": "application/x-mcap", ".db3": "application/x-sqlite3"}
_EXTENSIONS = {".mcap": ".mcap", ".db3": ".sqlite3"}  # the gateway's download names


def _read_only(
    handler: Callable[[Request], Awaitable[Response]],
) -> Callable[[Request], Awaitable[Response]]:
    async def endpoint(request: Request) -> Response:
        if request.method not in READ_METHODS:
            raise method_not_allowed(request.method, request.url.path)
        body = request.headers.get("content-length")
        if body is not None and body != "0":
            raise GatewayError(413, "invalid-request", "A read-only route takes no request body")
        return await handler(request)

    return endpoint


def build_app(
    served: ServedRecording,
    *,
    speed: float = 1.0,
    cors: Sequence[str] = (),
    max_streams: int = 2,
) -> ASGIApp:
    """The ASGI application answering the gateway's read-only routes over ``served``."""
    gateway = GatewayApp(served, speed=speed, max_streams=max_streams)
    table: list[tuple[str, Callable[[Request], Awaitable[Response]]]] = [
        ("", gateway.root),
        ("/", gateway.root),
        ("/version-info", gateway.version_info),
        ("/health", gateway.health),
        ("/x-medkit/recording", gateway.recording),
        ("/faults/stream", gateway.fault_stream),
        ("/faults", gateway.faults),
        ("/{kind}", gateway.collection),
        ("/{kind}/{entity_id}", gateway.detail),
        ("/{kind}/{entity_id}/faults", gateway.entity_faults),
        ("/{kind}/{entity_id}/faults/{code}", gateway.fault),
        ("/{kind}/{entity_id}/bulk-data", gateway.bulk_categories),
        ("/{kind}/{entity_id}/bulk-data/{category}", gateway.bulk_descriptors),
        ("/{kind}/{entity_id}/bulk-data/{category}/{file_id}", gateway.bulk_download),
        ("/{kind}/{entity_id}/{relation}", gateway.related),
    ]
    routes = [Route(API + path, _read_only(fn), methods=ALL_METHODS) for path, fn in table]

    async def gateway_error(request: Request, exc: Exception) -> Response:
        assert isinstance(exc, GatewayError)
        headers = {"Allow": "GET, HEAD"} if exc.status == 405 else None
        return _json(exc.status, error_body(exc), headers)

    async def http_error(request: Request, exc: Exception) -> Response:
        assert isinstance(exc, HTTPException)
        if exc.status_code == 405:
            err = method_not_allowed(request.method, request.url.path)
        else:
            err = unknown_route(request.url.path)
        return _json(err.status, error_body(err))

    async def internal_error(request: Request, exc: Exception) -> Response:
        err = GatewayError(500, "internal-error", "The server could not answer this request")
        return _json(500, error_body(err))

    middleware = []
    if cors:
        middleware.append(
            Middleware(
                CORSMiddleware,
                allow_origins=list(cors),
                allow_methods=["GET", "HEAD"],
                allow_headers=["Last-Event-ID", "Content-Type", "Authorization"],
            )
        )
    app = Starlette(
        routes=routes,
        middleware=middleware,
        exception_handlers={
            GatewayError: gateway_error,
            HTTPException: http_error,
            Exception: internal_error,
        },
    )
    return MomentPrefix(app)
