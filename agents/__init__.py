"""The agents: training (stable-baselines3, Ray RLlib), evaluation, the benchmark and the agents
that ship, run from the repository root (``python -m agents.NAME``). ``agents/README.md`` lists
the modules bottom up; the docs' agents page says how to use them.
"""
