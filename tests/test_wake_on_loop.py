"""A connection's message event is woken on its event loop only (``server.wake_on_loop``): viser's
buffer also sets it from the thread that writes, and an ``asyncio.Event`` set there while the loop
adds or removes a waiter raised "deque mutated during iteration" in the middle of a tab's update."""

from __future__ import annotations

import asyncio
import threading
import time

from shoal.app.server import _LoopEvent

from browser.browser_helpers import wait_until
from viser_wire import WireClient


def _loop_in_a_thread() -> tuple[asyncio.AbstractEventLoop, threading.Thread]:
    loop = asyncio.new_event_loop()
    thread = threading.Thread(target=loop.run_forever, daemon=True)
    thread.start()
    return loop, thread


def _waiting(loop: asyncio.AbstractEventLoop, event: asyncio.Event):
    """A waiter of ``event`` on ``loop`` (a concurrent future, done once the event is set)."""
    future = asyncio.run_coroutine_threadsafe(event.wait(), loop)
    wait_until(lambda: len(event._waiters) == 1, timeout=5, what="the waiter")  # type: ignore[attr-defined]
    return future


def test_a_set_off_the_loop_leaves_the_waiters_to_the_loop():
    loop, thread = _loop_in_a_thread()
    try:
        plain = asyncio.Event()
        plain_waiter = _waiting(loop, plain)
        plain.set()  # (what viser's buffer does from the ticker's thread: the waiters are touched here)
        assert plain.is_set()

        ours = asyncio.Event()
        ours.__class__ = _LoopEvent
        ours._shoal_loop = loop  # type: ignore[attr-defined]
        waiter = _waiting(loop, ours)
        ours.set()  # off the loop: nothing, not even the flag
        time.sleep(0.1)
        assert not waiter.done() and not ours.is_set() and len(ours._waiters) == 1  # type: ignore[attr-defined]
        loop.call_soon_threadsafe(ours.set)  # (what the buffer does next: the loop wakes the waiter)
        assert waiter.result(timeout=5) is True
        assert plain_waiter.result(timeout=5) is True
    finally:
        loop.call_soon_threadsafe(loop.stop)
        thread.join(5)
        loop.close()


def test_every_connection_of_the_app_gets_it_and_its_updates_arrive(server):
    client = WireClient(server.port, decode=True)
    try:
        wait_until(lambda: server.tabs, what="a tab")
        buffer = next(iter(server.viser.get_clients().values())).gui._websock_interface.get_message_buffer()
        assert type(buffer.message_event) is _LoopEvent and buffer.message_event._shoal_loop is buffer.event_loop
        tab = next(iter(server.tabs.values()))
        tab.session.play()
        frames = client.counts()[2]
        wait_until(lambda: client.counts()[2] > frames + 20, timeout=60, what="frames while the tab plays")

        # writers on four threads at once, as the ticker, callbacks and a lecture's broadcast write
        errors: list[BaseException] = []

        def write(n: int) -> None:
            from viser import _messages

            try:
                for i in range(n):
                    buffer.push(_messages.RunJavascriptMessage(source=f"void {i};"))
            except BaseException as err:  # noqa: BLE001 (collected: the test says which)
                errors.append(err)

        writers = [threading.Thread(target=write, args=(3000,)) for _ in range(4)]
        for w in writers:
            w.start()
        for w in writers:
            w.join(60)
        assert not errors, errors
        frames = client.counts()[2]
        wait_until(lambda: client.counts()[2] > frames + 20, timeout=60, what="frames after the writers")
    finally:
        client.close()
