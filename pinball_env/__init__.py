"""A pinball table for reinforcement learning, moved by swept (continuous) collision."""

__version__ = "0.1.0"
