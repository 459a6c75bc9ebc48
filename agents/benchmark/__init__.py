"""The benchmark: named methods x training seeds under the protocol (``pinball_env.protocol``).

    python -m agents.benchmark                                   # every method, seeds 0-4
    python -m agents.benchmark --methods ppo-v1 heuristic-v1 --seeds 0 1 2 --parallel 2
    python -m agents.benchmark --address auto                    # each run a Ray task
    python -m agents.benchmark --merge docs/benchmark.json       # the published runs reused
    python -m agents.benchmark --tiny --out /tmp/bench           # a minute: the whole pipeline

A method (:data:`METHODS`) is a training config of ``configs/agents/`` on a protocol env, or a
baseline (``random``, ``heuristic``; one run, no training). Each method x seed is a job: train
the config with ``seed=S`` for the protocol's frames (``total_frames``, no time limit) into
``OUT/METHOD/seedS/RUN`` (``agents.train``'s run folder), then evaluate the run's model on the
protocol's games (``RUN/protocol_eval``: ``agents.evaluate --protocol``). Jobs are resumable: a
run with its evaluation is reused, a run without a model goes on from its last checkpoint, and
a run whose config is not the one the job would train is an error (delete it or pick another
``--out``). Locally the jobs run one at a time (``--parallel N``: N at once, each in its own
process); with ``--address`` each is a Ray task with its own CPUs (the config's threads) on the
cluster, which gets this code, trains and evaluates in a scratch folder and sends the run folder
back (a partial run is sent out to go on with), so that a cluster gives the whole table in the
time of one run.

Then the results are aggregated into ``OUT``:

- ``benchmark.json``: the protocol, the commit, and per method its env, config, runs (seed,
  score mean and IQM, frames, minutes of training) and the protocol's metrics
  (``pinball_env.protocol.aggregate``: mean and IQM of the score and of the normalised score,
  with stratified bootstrap 95% intervals), and the reference means measured (random and the
  heuristic, per env);
- ``benchmark.csv`` (a row per method), ``runs.csv`` (a row per run) and ``benchmark.md`` (the
  table in Markdown);
- ``scores.png`` (the score distribution of every method's games, per env) and
  ``profiles.png`` (performance profiles of the normalised scores with 95% bands, per env).

``--merge BENCHMARK_JSON ...`` takes the runs OUT lacks from earlier benchmarks (another
machine's, or the results published in ``docs/benchmark.json``: run folders are outputs, the
published file keeps every run's game scores, its commit and the digest of its config); their
jobs are not run again, and a file of another protocol or a run of a config changed since is
refused. A table can so grow over machines and sessions, a run at a time.

``--ship METHOD[=NAME] ...`` makes each method's best run (by its validation games, never the
held-out ones) a pretrained agent that ships with the project: ``agents/pretrained/NAME.zip``
and its card ``NAME.json`` (method, config, commit, training, scores under the protocol),
loadable as ``pretrained:NAME`` (``agents.policy.load_policy``). NAME is the method's unless
given (``--ship METHOD=NAME``; the shipped agents carry their method's name, and the names they
shipped under before load as aliases: ``agents.policy.PRETRAINED_ALIASES``). The chosen run
must be in OUT, where its model is; ``--ship-from-out`` ships the best run there when
a better merged one's model is gone, and its card says so.

``--tiny`` trains a few thousand frames of small settings and plays a few games: the whole
pipeline in about a minute, for tests.
The package, a module per concept: :mod:`~agents.benchmark.methods` (the rows and their
budgets), :mod:`~agents.benchmark.jobs` (a method x seed trained and evaluated, locally or as a
Ray task, and resumed), :mod:`~agents.benchmark.results` (merging, the published JSON and CSV),
:mod:`~agents.benchmark.tables` and :mod:`~agents.benchmark.plots`,
:mod:`~agents.benchmark.shipping` (``--ship``) and :mod:`~agents.benchmark.cli` (the command).
"""
