"""The agents: training (stable-baselines3, Ray RLlib), evaluation, the benchmark and the agents
that ship, run from the repository root (``python -m agents.NAME``). ``agents/README.md`` lists
the modules bottom up; the docs' agents page says how to use them.

Importing the package makes torch's OpenMP threads wait passively (``OMP_WAIT_POLICY=PASSIVE``,
unless the environment sets it; torch reads it when it is first imported, which ``agents``
does only later): by default they spin between the small parallel regions of a training step,
and on a machine shared with another CPU-bound process the spinning threads took the cores the
others waited for, so training fell to about a third of its speed (``python -m benchmarks.speed
--only sb3_ppo_scale_v2 sb3_ppo_scale_v2_shared``: 0.3 of its rate alone before, 1.0 after, at
a few percent of its rate alone). The numbers a training computes are the same either way.
"""

import os

os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
