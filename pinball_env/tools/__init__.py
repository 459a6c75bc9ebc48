"""Command-line tools, each run as ``python -m pinball_env.tools.NAME``:

- ``demo``: the scripted heuristic plays (a window, or headless with a PNG of the last frame);
- ``plot``: matplotlib pictures of a table and a ball's path on it;
- ``crosscheck``: the swept physics against pymunk, scenario by scenario, with a report;
- ``benchmark``: speed of the world step and of the env, as a table and JSON.
"""
