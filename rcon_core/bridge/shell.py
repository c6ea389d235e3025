"""``SessionShell``: the async side of the rosbridge :class:`~rcon_core.bridge.session.Session`.

The session (``session.py``) is sans-I/O: it decides, the shell does.  What lives here and only here:

* writing: the session's outbox is drained to the current link as soon as a frame is put in it
  (``session.wake``), in order; a publish goes straight to the link's ``write``, or ``send_by`` with its
  deadline for a command, which the shell lends the session while the link is attached (refused at once while the link is degraded or stalling, dropped by the writer when it waited
  too long: ``linkbase.py``, ``freshness.py``);
* the link coming and going: :meth:`attached` hands the guard the loop (a view-only mark set from another
  thread is applied there) and lets the session restore; :meth:`detached` drops what the link still
  queued (``stats.dropped_on_disconnect``) and lets the session fail what waited;
* futures, timeouts and tasks: :meth:`call_service` (an ``asyncio`` future per call, the call's budget,
  waiting for the link inside it), :meth:`spawn` for the work of the session's parts (a handler that
  returns an awaitable, a type lookup before a cbor subscription, a goal's existence check), and the
  held watch's timer;
* building those parts (:meth:`build_parts`): services this client provides, action goals, actions this
  client provides and the subscriber, each given the session's ``send`` and the shell's ``spawn``.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING, Any

from .action_server import ProvidedActions
from .goals import Goals
from .services import ProvidedServices
from .session import Session
from .subscribe import Subscriber

if TYPE_CHECKING:
    from .linkbase import Link

log = logging.getLogger(__name__)


def later(delay: float, fn: Callable[[], Any]) -> Any:
    """``fn()`` after ``delay`` s on the running loop; nothing without one (the held watch's ``schedule``)."""
    try:
        return asyncio.get_running_loop().call_later(delay, fn)
    except RuntimeError:
        return None


class SessionShell:
    """Drains one session's outbox to the link and keeps its futures and tasks (see the module docstring)."""

    def __init__(self, session: Session, host: Any) -> None:
        self.session = session
        self.host = host  # call_timeout and wait_connected(); the parts read registry, rosapi, url (session.Host)
        self.link: Link | None = None
        self.tasks: set[asyncio.Task[Any]] = set()
        session.wake = self.flush
        self.build_parts(session, host, self.spawn)

    @staticmethod
    def build_parts(session: Session, host: Any, spawn: Callable[[Awaitable[Any]], Any]) -> None:
        """Give ``session`` its parts (``Session.use_parts``), running their async work through ``spawn``."""
        session.use_parts(ProvidedServices(session.send, spawn, host), Goals(session.send, spawn, host),
                          ProvidedActions(session.send), Subscriber(session, host, spawn))

    # ================================================================== frames out

    def flush(self) -> None:
        """Write every frame of the session's outbox to the link; without one they stay, and the session drops
        and counts them when it is detached."""
        link = self.link
        session = self.session
        if link is None:
            return
        for out in session.take():
            if out.deadline is None:
                link.write(out.data)
            elif not link.send_by(out.data, out.pub, out.deadline):  # its own now: the frame may have waited
                session.drop_stale(out.pub, counted_sent=True)

    # ================================================================== the link comes and goes

    def attached(self, link: Link) -> None:
        """A fresh connection, ``auth`` sent: the session restores through it."""
        self.link = link
        session = self.session
        session.write, session.send_by = link.write, link.send_by  # a publish: one call to the link
        session.guard.attached(asyncio.get_running_loop())
        session.attached()

    def detached(self, link: Link) -> None:
        """The link is gone: what it still queued is dropped; the session fails what waited."""
        self.link = None
        self.session.write = self.session.send_by = None
        dropped = link.drop_queue()
        if dropped:
            self.session.stats.dropped_on_disconnect += dropped
        self.session.detached()

    # ================================================================== tasks

    def spawn(self, coro: Awaitable[Any]) -> asyncio.Task[Any]:
        task = asyncio.ensure_future(coro)
        self.tasks.add(task)
        task.add_done_callback(self._task_done)
        return task

    def _task_done(self, task: asyncio.Task[Any]) -> None:
        self.tasks.discard(task)
        if not task.cancelled() and task.exception() is not None:
            log.error("background task failed: %s", task.exception(), exc_info=task.exception())

    def cancel_tasks(self) -> None:
        for t in list(self.tasks):
            t.cancel()

    # ================================================================== service calls

    async def call_service(self, name: str, args: dict[str, Any] | list | None = None,
                           timeout: float | None = None) -> Any:
        """Call a service; returns its ``values``.  Raises ServiceError / ServiceTimeoutError (the decision
        is the session's: "service calls")."""
        session = self.session
        call = session.open_call(name, args, timeout)
        budget = self.host.call_timeout if timeout is None else timeout
        fut: asyncio.Future[Any] = asyncio.get_running_loop().create_future()

        def done(values: Any, error: BaseException | None) -> None:
            if not fut.done():
                if error is None:
                    fut.set_result(values)
                else:
                    fut.set_exception(error)

        call.done = done
        try:
            async with asyncio.timeout(budget):
                await self.host.wait_connected()
                session.start_call(call)
                return await fut
        except TimeoutError:
            raise session.timed_out(call, budget) from None
        finally:
            session.forget_call(call)
