"""``python -m agents.benchmark``: see :mod:`agents.benchmark.cli`."""

from agents.benchmark.cli import main

if __name__ == "__main__":
    main()
