"""The browser page of ``python -m pinball_env.tools.serve``: what it is sent and what it runs.

- ``stream.py``: a table's geometry (sent once) and each frame's state (streamed), as JSON for
  the page's canvas, and the page's keys (the play tool's, by their browser names);
- ``sessions.py``: the games behind a page, stepped one frame per tick: played from the page's
  buttons (:class:`PlaySession`), played by a player (:class:`WatchSession`), or a recording
  replayed on a timeline (:class:`ReplaySession`), and the messages a page may send them;
- ``static/``: the page itself (``index.html``, ``app.js``, ``style.css``): plain files, no build.

Nothing here needs the web stack: ``pinball_env.tools.serve`` (the ``web`` extra) serves them.
"""
