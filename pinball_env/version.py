"""The package's version, declared once (``pinball_env.__version__``): a recording and a saved
game (``envs.states``) carry it, and refuse to be played by another."""

__version__ = "0.1.0"
