"""Optional dependencies: each named once with the extra that installs it, imported only when
it is needed, and a missing one reported in one line that fits an installed package as well as
a checkout."""

import importlib
from types import ModuleType

from gymnasium.error import DependencyNotInstalled

# The module -> what to pip install for it, and the extra of pinball-env that has it.
OPTIONAL: dict[str, tuple[str, str]] = {
    "pygame": ("pygame", "render"),
    "matplotlib": ("matplotlib", "plot"),
    "pymunk": ("pymunk", "crosscheck"),
    "stable_baselines3": ("stable-baselines3", "train"),
    "tqdm": ("tqdm", "train"),
    "imageio": ("imageio imageio-ffmpeg", "train"),
    "moviepy": ("moviepy", "wrappers"),
    "cv2": ("opencv-python-headless", "wrappers"),
    "ray": ('"ray[rllib]"', "distributed"),
    "starlette": ("starlette", "web"),
    "uvicorn": ("uvicorn", "web"),
    "websockets": ("websockets", "web"),
}


class MissingDependency(DependencyNotInstalled, ImportError):
    """An optional dependency is not installed; the message says what to install."""


def missing_message(module: str) -> str:
    """``"M is missing: pip install P (in a checkout: pip install -e ".[EXTRA]")"``."""
    package, extra = OPTIONAL[module]
    return (
        f"{module} is missing: pip install {package} (in a checkout of pinball-env: pip install "
        f'-e ".[{extra}]")'
    )


def require(*modules: str) -> ModuleType:
    """Import ``modules`` (names in :data:`OPTIONAL`), returning the last; raise
    :class:`MissingDependency` naming the first one missing."""
    imported: ModuleType | None = None
    for module in modules:
        if module not in OPTIONAL:
            raise KeyError(f"{module!r} is not a declared optional dependency")
        try:
            imported = importlib.import_module(module)
        except ImportError as error:
            raise MissingDependency(missing_message(module)) from error
    if imported is None:
        raise TypeError("require() needs the name of a module")
    return imported
