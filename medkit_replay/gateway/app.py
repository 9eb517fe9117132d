"""The Starlette application: the gateway's read-only routes over one ServedRecording.

Routes, ``at`` moments (query or ``/at/{seconds}`` base), 404/405 as GenericError, CORS and bounds
live here; the bodies come from ``faults_json``, ``discovery_json`` and ``stream``.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from starlette.applications import Starlette
from starlette.exceptions import HTTPException
from starlette.middleware import Middleware
from starlette.middleware.cors import CORSMiddleware
from starlette.responses import FileResponse, Response
from starlette.routing import Route

from medkit_replay.gateway import discovery_json
from medkit_replay.gateway.bulk_json import (
    bulk_categories_body,
    bulk_source_filters,
    rosbag_descriptors_body,
    rosbag_download,
)
from medkit_replay.gateway.detail_json import fault_detail_body, recordings_held_at
from medkit_replay.gateway.entities import KINDS
from medkit_replay.gateway.errors import (
    ERR_INTERNAL_ERROR,
    ERR_INVALID_REQUEST,
    ERR_RESOURCE_NOT_FOUND,
    ID_FIELDS,
    GatewayError,
    body_bytes,
    bulk_data_not_found,
    error_body,
    error_status,
    invalid_parameter,
    method_not_allowed,
    unknown_category,
)
from medkit_replay.gateway.faults_json import (
    entity_fault_list_body,
    fault_list_body,
    parse_status_filter,
    query_bool,
    scoped_fault,
)
from medkit_replay.gateway.stream import EventStream

if TYPE_CHECKING:
    from collections.abc import Awaitable, Callable, Sequence

    from starlette.requests import Request
    from starlette.types import ASGIApp, Receive, Scope, Send

    from medkit_replay.captures import EvidenceRecording
    from medkit_replay.gateway.entities import Entity
    from medkit_replay.gateway.recording import ServedRecording
    from medkit_replay.model import FaultSnapshot

API = "/api/v1"
READ_METHODS = frozenset({"GET", "HEAD"})
ALL_METHODS = ["GET", "HEAD", "POST", "PUT", "PATCH", "DELETE"]
MAX_RESPONSE_BYTES = 256 * 1024 * 1024
"""The largest JSON body answered (a fault list of this size means something is wrong)."""
MAX_REQUEST_HEAD_BYTES = 16 * 1024
"""The largest request line and headers answered (431 beyond); every route is a GET."""
MOMENT_PREFIX = "/at/"
ROSBAG_CATEGORY = "rosbags"
SUB_ENTITIES = {"areas": "subareas", "components": "subcomponents"}
"""The nested collections whose members have bulk-data routes of their own."""
_NESTED = "/{kind}/{parent_id}/{nested}/{entity_id}"


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
                await _json(error_status(err), error_body(err))(scope, receive, send)
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
        raise invalid_parameter(
            "Invalid moment", {"parameter": "at", "value": text[:64],
                               "details": "seconds from the recording's start"}
        )  # fmt: skip
    return value


def _asked_seconds(request: Request) -> float | None:
    """The moment a request names: ``?at=`` first, else the ``/at/`` base; None: neither."""
    text = request.query_params.get("at")
    if text is not None:
        return _seconds(text)
    prefixed = request.scope.get("medkit_at")
    return prefixed if isinstance(prefixed, float) else None


def _json(status: int, body: object, headers: dict[str, str] | None = None) -> Response:
    data = body_bytes(body)
    if len(data) > MAX_RESPONSE_BYTES:
        err = GatewayError(
            500, "x-medkit-response-too-large", "The answer exceeds the server's response bound"
        )
        data, status = body_bytes(error_body(err)), err.status
    return Response(data, status, headers=headers, media_type="application/json")


class GatewayApp:
    """The routes' handlers over one recording (one instance per server)."""

    def __init__(self, served: ServedRecording, *, speed: float, max_streams: int) -> None:
        self.served = served
        self.stream = EventStream(served, speed=speed, max_clients=max_streams)

    # -- what a request names --------------------------------------------------------------

    def moment(self, request: Request) -> int:
        """Bag time the request asks about: ``?at=``, else the ``/at/`` prefix, else ``--at``."""
        return self.served.moment(_asked_seconds(request))

    def entity(self, request: Request) -> Entity:
        """The entity of a ``/{kind}/{id}/...`` route (a nested sub-area's or sub-component's
        when the route names one), refused as the gateway refuses it."""
        params = request.path_params
        kind = params["kind"]
        if kind not in KINDS:
            raise _unknown_route(request)
        nested = params.get("nested")
        if nested is not None:
            if nested != SUB_ENTITIES.get(kind):
                raise _unknown_route(request)
            discovery_json.route_entity(self.served.entities, kind, params["parent_id"])
            return discovery_json.route_entity(self.served.entities, kind, params["entity_id"])
        return discovery_json.route_entity(self.served.entities, kind, params["entity_id"])

    def held(self, t_ns: int) -> tuple[list[EvidenceRecording], dict[str, FaultSnapshot]]:
        """The black-box recordings and the faults (by code) the manager holds at ``t_ns``."""
        recordings = recordings_held_at(self.served.result.recordings, t_ns)
        return recordings, {f.fault_code: f for f in self.served.history.faults_at(t_ns)}

    # -- root, health, the recording -------------------------------------------------------

    async def root(self, request: Request) -> Response:
        return _json(200, discovery_json.root_body())

    async def version_info(self, request: Request) -> Response:
        return _json(200, discovery_json.version_info_body())

    async def health(self, request: Request) -> Response:
        return _json(200, discovery_json.health_body(self.moment(request)))

    async def recording(self, request: Request) -> Response:
        return _json(200, self.served.recording_facts())

    # -- discovery -------------------------------------------------------------------------

    async def collection(self, request: Request) -> Response:
        kind = request.path_params["kind"]
        if kind not in KINDS:
            raise _unknown_route(request)
        return _json(200, discovery_json.list_body(self.served.entities, kind))

    async def detail(self, request: Request) -> Response:
        entity = self.entity(request)
        return _json(200, discovery_json.detail_body(self.served.entities, entity))

    async def related(self, request: Request) -> Response:
        kind, relation = request.path_params["kind"], request.path_params["relation"]
        if kind not in KINDS or relation not in discovery_json.RELATIONS[kind]:
            raise _unknown_route(request)
        entities = self.served.entities
        owner = discovery_json.relation_owner(entities, kind, request.path_params["entity_id"])
        return _json(200, discovery_json.relation_body(entities, owner, relation))

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
            include_muted=query_bool(query.get("include_muted")),
            include_clusters=query_bool(query.get("include_clusters")),
        )
        return _json(200, body)

    async def entity_faults(self, request: Request) -> Response:
        entity = self.entity(request)
        status = parse_status_filter(
            request.query_params.get("status"), {ID_FIELDS[entity.kind]: entity.id}
        )
        t_ns = self.moment(request)
        entities, history = self.served.entities, self.served.history
        body = entity_fault_list_body(
            history.faults_at(t_ns),
            history.correlation_at(t_ns),
            status,
            kind=entity.kind,
            entity_id=entity.id,
            sources=entities.fault_sources(entity),
            source_id=entity.fqn,
            component_count=len(entities.components_in(entity.id)),
        )
        return _json(200, body)

    async def fault(self, request: Request) -> Response:
        entity = self.entity(request)
        code = request.path_params["code"]
        t_ns = self.moment(request)
        served = self.served
        found = scoped_fault(
            code,
            served.history.fault_at(code, t_ns),
            kind=entity.kind,
            entity_id=entity.id,
            sources=served.entities.fault_sources(entity),
            max_code_length=served.max_code_length,
        )
        body = fault_detail_body(
            found,
            served.captures_at(code, t_ns),
            recordings_held_at(served.result.recordings, t_ns),
            kind=entity.kind,
            entity_id=entity.id,
            rosbag_format=served.rosbag_format,
            retain_on_clear=served.retain_on_clear,
            bag_sizes=served.bag_sizes,
        )
        return _json(200, body)

    # -- bulk data -------------------------------------------------------------------------

    async def bulk_categories(self, request: Request) -> Response:
        self.entity(request)
        return _json(200, bulk_categories_body())

    def _bulk_scope(self, request: Request) -> tuple[Entity, list[str], int]:
        entity = self.entity(request)
        category = request.path_params["category"]
        if category != ROSBAG_CATEGORY:
            raise unknown_category(category)
        sources = self.served.entities.fault_sources(entity)
        fallback = entity.fqn or entity.namespace
        return entity, bulk_source_filters(entity.kind, sources, fallback), self.moment(request)

    async def bulk_descriptors(self, request: Request) -> Response:
        _, scope, t_ns = self._bulk_scope(request)
        served = self.served
        body = rosbag_descriptors_body(
            *self.held(t_ns), scope, rosbag_format=served.rosbag_format, bag_sizes=served.bag_sizes
        )
        return _json(200, body)

    async def bulk_download(self, request: Request) -> Response:
        entity, scope, t_ns = self._bulk_scope(request)
        served = self.served
        found = rosbag_download(
            *self.held(t_ns),
            request.path_params["file_id"],
            entity_id=entity.id,
            scope=scope,
            rosbag_format=served.rosbag_format,
            max_code_length=served.max_code_length,
        )
        # Only a clip this replay wrote: looked up by its id, never a path from the request.
        path = served.clips.get(found.recording.recording_id)
        if path is None:
            raise bulk_data_not_found(request.path_params["file_id"])
        return FileResponse(path, media_type=found.mimetype, filename=found.filename)

    # -- the event stream ------------------------------------------------------------------

    async def fault_stream(self, request: Request) -> Response:
        # The stream starts at a moment only when one is named (not at --at's default).
        start = _asked_seconds(request)
        return self.stream.response(
            request.headers.get("last-event-id"),
            self.served.moment(start) if start is not None else None,
        )


def _unknown_route(request: Request) -> GatewayError:
    return GatewayError(
        404, ERR_RESOURCE_NOT_FOUND, "Resource not found", {"path": request.url.path[:256]}
    )


def _read_only(
    handler: Callable[[Request], Awaitable[Response]],
) -> Callable[[Request], Awaitable[Response]]:
    async def endpoint(request: Request) -> Response:
        head = len(request.scope.get("raw_path") or b"") + len(request.scope["query_string"])
        head += sum(len(name) + len(value) for name, value in request.scope["headers"])
        if head > MAX_REQUEST_HEAD_BYTES:
            raise GatewayError(
                431, ERR_INVALID_REQUEST, "Request line and headers exceed the server's bound",
                {"max_bytes": MAX_REQUEST_HEAD_BYTES},
            )  # fmt: skip
        if request.method not in READ_METHODS:
            raise method_not_allowed(request.method, request.url.path[:256])
        length = request.headers.get("content-length", "0")
        if length != "0" or "transfer-encoding" in request.headers:
            raise GatewayError(413, ERR_INVALID_REQUEST, "A read-only route takes no request body")
        return await handler(request)

    return endpoint


def build_app(
    served: ServedRecording,
    *,
    speed: float = 1.0,
    cors: Sequence[str] = (),
    max_streams: int = 2,
) -> ASGIApp:
    """The ASGI application answering the gateway's read-only routes over ``served``.

    ``max_streams``: event streams open at once (upstream's ``sse.max_clients``, 2).
    """
    gateway = GatewayApp(served, speed=speed, max_streams=max_streams)
    entity = "/{kind}/{entity_id}"
    bulk = [("/bulk-data", gateway.bulk_categories),
            ("/bulk-data/{category}", gateway.bulk_descriptors),
            ("/bulk-data/{category}/{file_id}", gateway.bulk_download)]  # fmt: skip
    table: list[tuple[str, Callable[[Request], Awaitable[Response]]]] = [
        ("", gateway.root),
        ("/", gateway.root),
        ("/version-info", gateway.version_info),
        ("/health", gateway.health),
        ("/x-medkit/recording", gateway.recording),
        ("/faults/stream", gateway.fault_stream),
        ("/faults", gateway.faults),
        ("/{kind}", gateway.collection),
        (entity, gateway.detail),
        (entity + "/faults", gateway.entity_faults),
        (entity + "/faults/{code}", gateway.fault),
        # a sub-area's or sub-component's bulk data has routes of its own
        *((base + tail, fn) for base in (entity, _NESTED) for tail, fn in bulk),
        (entity + "/{relation}", gateway.related),
    ]
    routes = [Route(API + path, _read_only(fn), methods=ALL_METHODS) for path, fn in table]

    async def gateway_error(request: Request, exc: Exception) -> Response:
        assert isinstance(exc, GatewayError)
        status = error_status(exc)
        headers = {"Allow": "GET, HEAD"} if status == 405 else None
        return _json(status, error_body(exc), headers)

    async def http_error(request: Request, exc: Exception) -> Response:
        assert isinstance(exc, HTTPException)
        if exc.status_code == 405:
            return await gateway_error(request, method_not_allowed(request.method, ""))
        return await gateway_error(request, _unknown_route(request))

    async def internal_error(request: Request, exc: Exception) -> Response:
        err = GatewayError(500, ERR_INTERNAL_ERROR, "The server could not answer this request")
        return _json(500, error_body(err))

    middleware = []
    if cors:
        middleware.append(
            Middleware(
                CORSMiddleware,
                allow_origins=list(cors),
                allow_methods=["GET", "HEAD"],
                allow_headers=["Accept", "Authorization", "Content-Type", "Last-Event-ID"],
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
