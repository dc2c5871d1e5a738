"""The interactive view as a web page on 127.0.0.1 (``splineviz serve``, notebooks).

An aiohttp application serves one page (``page.html`` beside this module) and a websocket.
The page sends the user's actions as JSON (``{"type": "orbit", "dx", "dy", "t"}``,
``"press"``, ``"release"``, ``"zoom"``, ``{"type": "set", "name", "value"}``; ``t`` is the
page's clock at the event); the server answers with frames
(``{"type": "frame", "exact", "t", "seq", "state", "png"}``: a base64 PNG, the state of
:meth:`RemoteView.state` including the camera, and the ``t`` of the newest action it shows,
from which the page measures its round trip).

All rendering runs in one thread (VTK is not thread safe). Actions that arrive while a frame
is made are applied together before the next one (a drag's steps coalesce), a preview follows
every batch, and the exact frame follows :data:`REFINE_DELAY_S` after the last action while
no mouse button is held. ``GET /state`` reports the camera and the controls (JSON).
"""

from __future__ import annotations

import asyncio
import base64
import json
import threading
from concurrent.futures import ThreadPoolExecutor
from importlib import resources

from splineviz.core.errors import SplinevizError
from splineviz.model import Scene
from splineviz.web.png import png_bytes
from splineviz.web.view import RemoteView, Shot, WebViewError

#: seconds without an action, and no button held, before the exact frame is made
REFINE_DELAY_S = 0.3
#: the only address served: the view is for this machine (reach it over SSH port forwarding)
HOST = "127.0.0.1"


class ServeError(SplinevizError, OSError):
    """The server could not start (port in use...)."""


def page_html() -> str:
    """The page's HTML (with its script)."""
    return resources.files("splineviz.web").joinpath("page.html").read_text(encoding="utf-8")


class ViewServer:
    """Serve ``scene``'s view (see module docstring); :meth:`start` in a running event loop.

    Parameters
    ----------
    scene : splineviz.model.Scene
    size : (width, height)
    port : int
        0: a free port (:attr:`port` tells which after :meth:`start`).
    device : str or None
    """

    def __init__(self, scene: Scene, size=(640, 480), port: int = 0, device=None):
        self.view = RemoteView(scene, size, device)
        self.port = int(port)
        self._executor = ThreadPoolExecutor(1, thread_name_prefix="splineviz-render")
        self._pending: list[dict] = []
        self._wake: asyncio.Event | None = None
        self._clients: set = set()
        self._button_down = False
        self._exact_due = True
        self._seq = 0
        self._task = None
        self._runner = None
        self._last: dict | None = None
        #: the page's clock at the newest action shown (0: none yet)
        self._newest_t = 0.0

    @property
    def url(self) -> str:
        return f"http://{HOST}:{self.port}/"

    async def start(self) -> None:
        from aiohttp import web

        app = web.Application()
        app.router.add_get("/", self._page)
        app.router.add_get("/state", self._state)
        app.router.add_get("/ws", self._websocket)
        self._runner = web.AppRunner(app, access_log=None)
        await self._runner.setup()
        site = web.TCPSite(self._runner, HOST, self.port)
        try:
            await site.start()
        except OSError as exc:
            await self._runner.cleanup()
            raise ServeError(f"cannot serve on {HOST}:{self.port}: {exc.strerror or exc}") \
                from None
        self.port = self._runner.addresses[0][1]
        self._wake = asyncio.Event()
        self._task = asyncio.get_running_loop().create_task(self._render_loop())

    async def stop(self) -> None:
        if self._task is not None:
            self._task.cancel()
            try:
                await self._task
            except asyncio.CancelledError:
                pass
        for ws in list(self._clients):
            await ws.close()
        if self._runner is not None:
            await self._runner.cleanup()
        await asyncio.get_running_loop().run_in_executor(self._executor, self.view.close)
        self._executor.shutdown()

    # -- requests ------------------------------------------------------------------------

    async def _page(self, request):
        from aiohttp import web

        return web.Response(text=page_html(), content_type="text/html")

    async def _state(self, request):
        from aiohttp import web

        state = await self._run(lambda: {**self.view.state(), "controls": self.view.controls()})
        return web.json_response(state)

    async def _websocket(self, request):
        from aiohttp import WSMsgType, web

        ws = web.WebSocketResponse(max_msg_size=1 << 16)
        await ws.prepare(request)
        self._clients.add(ws)
        try:
            controls = await self._run(self.view.controls)
            await ws.send_json({"type": "controls", **controls})
            if self._last is not None:
                await ws.send_str(json.dumps(self._last))
            else:
                self._exact_due = True
                self._wake.set()
            async for msg in ws:
                if msg.type != WSMsgType.TEXT:
                    continue
                try:
                    action = json.loads(msg.data)
                except ValueError:
                    continue
                if isinstance(action, dict) and isinstance(action.get("type"), str):
                    self._pending.append(action)
                    self._wake.set()
        finally:
            self._clients.discard(ws)
        return ws

    # -- frames --------------------------------------------------------------------------

    async def _run(self, func, *args):
        return await asyncio.get_running_loop().run_in_executor(self._executor, func, *args)

    async def _render_loop(self) -> None:
        while True:
            if not self._pending:
                if self._exact_due and not self._button_down:
                    try:
                        await asyncio.wait_for(self._wake.wait(), REFINE_DELAY_S)
                    except TimeoutError:
                        t = self._newest_t
                        shot = await self._run(self.view.exact)
                        self._exact_due = False
                        await self._send(shot, t)
                        continue
                else:
                    await self._wake.wait()
            self._wake.clear()
            actions, self._pending = self._pending, []
            if not actions:
                continue
            errors = await self._run(self._apply, actions)
            self._newest_t = max((a.get("t", 0.0) for a in actions
                                  if isinstance(a.get("t", 0.0), int | float)),
                                 default=self._newest_t)
            for text in errors:
                await self._broadcast({"type": "error", "message": text})
            shot = await self._run(self.view.preview)
            self._exact_due = not shot.exact
            await self._send(shot, self._newest_t)

    def _apply(self, actions: list[dict]) -> list[str]:
        """Apply the page's actions in the render thread; returns error sentences."""
        errors = []
        dx = dy = 0.0
        for a in actions:
            kind = a["type"]
            try:
                if kind == "orbit":
                    dx += float(a.get("dx", 0.0))
                    dy += float(a.get("dy", 0.0))
                    continue
                if dx or dy:
                    self.view.orbit(dx, dy)
                    dx = dy = 0.0
                if kind == "press":
                    self._button_down = True
                elif kind == "release":
                    self._button_down = False
                elif kind == "zoom":
                    self.view.zoom(float(a.get("factor", 1.0)))
                elif kind == "set":
                    self.view.set(str(a.get("name")), a.get("value"))
            except (WebViewError, SplinevizError, ValueError, TypeError) as exc:
                errors.append(" ".join(str(exc).split()))
        if dx or dy:
            self.view.orbit(dx, dy)
        return errors

    async def _send(self, shot: Shot, t: float) -> None:
        # fast compression: the picture goes over the loopback, size hardly matters
        png = await self._run(png_bytes, shot.image, 1)
        self._seq += 1
        msg = {"type": "frame", "exact": shot.exact, "t": t, "seq": self._seq,
               "state": shot.state, "png": base64.b64encode(png).decode("ascii")}
        if shot.exact:
            self._last = msg
        await self._broadcast(msg)

    async def _broadcast(self, msg: dict) -> None:
        text = json.dumps(msg)
        for ws in list(self._clients):
            try:
                await ws.send_str(text)
            except (ConnectionError, RuntimeError):
                self._clients.discard(ws)


def serve_forever(scene: Scene, size=(640, 480), port: int = 0, device=None,
                  ready=None) -> None:
    """Serve until interrupted (Ctrl-C); ``ready(url)`` is called once the port is open."""

    async def main():
        server = ViewServer(scene, size, port, device)
        await server.start()
        if ready is not None:
            ready(server.url)
        try:
            await asyncio.Event().wait()
        finally:
            await server.stop()

    asyncio.run(main())


class InteractiveView:
    """A view served from a thread of this process (a notebook's kernel); a notebook shows
    its page in an ``<iframe>``. :meth:`stop` ends the server."""

    def __init__(self, server: ViewServer, loop: asyncio.AbstractEventLoop,
                 thread: threading.Thread):
        self.server = server
        self._loop = loop
        self._thread = thread

    @property
    def url(self) -> str:
        return self.server.url

    def _repr_html_(self) -> str:
        w, h = self.server.view.size
        return (f'<iframe src="{self.url}" width="{w + 40}" height="{h + 140}" '
                'style="border:0" title="splineviz view"></iframe>')

    def __repr__(self) -> str:
        return f"<splineviz interactive view at {self.url}>"

    def stop(self) -> None:
        if self._thread.is_alive():
            asyncio.run_coroutine_threadsafe(self.server.stop(), self._loop).result(timeout=30)
            self._loop.call_soon_threadsafe(self._loop.stop)
            self._thread.join(timeout=30)


def serve_in_thread(scene: Scene, size=(640, 480), port: int = 0, device=None
                    ) -> InteractiveView:
    """Start a :class:`ViewServer` of ``scene`` in a daemon thread; returns once it listens.

    The view changes the scene's nodes in its render thread: change the scene from the
    notebook while nobody drags, or make a new view."""
    loop = asyncio.new_event_loop()
    server = ViewServer(scene, size, port, device)
    started = threading.Event()
    failure: list[BaseException] = []

    def run():
        asyncio.set_event_loop(loop)
        try:
            loop.run_until_complete(server.start())
        except BaseException as exc:  # reported to the caller below
            failure.append(exc)
            started.set()
            return
        started.set()
        loop.run_forever()
        loop.close()

    thread = threading.Thread(target=run, name="splineviz-serve", daemon=True)
    thread.start()
    started.wait(timeout=60)
    if failure:
        raise failure[0]
    return InteractiveView(server, loop, thread)
