"""A real server of ``pinball_env.tools.serve`` on a free local port, for the page's tests
(tests/tools/test_serve.py, test_serve_browser.py)."""

import contextlib
import socket
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest


@contextlib.contextmanager
def running(app: Any) -> Iterator[str]:
    """Serve ``app`` (uvicorn, in a thread) on a free port of 127.0.0.1; yields its base URL."""
    uvicorn = pytest.importorskip("uvicorn", reason="the web extra is not installed")
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    from pinball_env.tools.serve import server_config  # (the tool's own settings)

    server = uvicorn.Server(server_config(app, "error", host="127.0.0.1", port=port))
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    for _ in range(600):  # started within a minute (the first env compiles nothing: cached)
        if server.started:
            break
        time.sleep(0.1)
    assert server.started, "the test server did not start"
    try:
        yield f"http://127.0.0.1:{port}"
    finally:
        server.should_exit = True
        thread.join(timeout=30)


@pytest.fixture
def serving() -> Callable[[Any], contextlib.AbstractContextManager[str]]:
    """``with serving(app) as url:``, the app served while the block runs."""
    return running
