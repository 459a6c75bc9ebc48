"""Command-line tools, each run as ``python -m pinball_env.tools.NAME``:

- ``demo``: the scripted heuristic plays (a window, or headless with a PNG of the last frame);
- ``plot``: matplotlib pictures of a table and a ball's path on it;
- ``crosscheck``: the swept physics against pymunk, scenario by scenario, with a report;
- ``play``: the keyboard in a window, recordings and their replays;
- ``tilt``: what nudging patterns trip Pinball-v1's and -v2's tilt;
- ``serve``: the game in a browser (play, watch, replay), for machines without a screen; the
  page and what it is sent are ``tools/web/``.

The speed benchmark is a developer's tool of the checkout: ``python -m benchmarks.speed``.
"""
