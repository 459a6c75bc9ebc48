"""Developer benchmarks, run from the repository root and not shipped in the wheel:
``python -m benchmarks.speed`` (the envs' and the kernel's speed, ``--compare REV`` against a
git revision; :mod:`benchmarks.compare`)."""
