"""``python -m pinball_env.tools.crosscheck``: see :mod:`.cli`."""

from pinball_env.tools.crosscheck.cli import main

main()
