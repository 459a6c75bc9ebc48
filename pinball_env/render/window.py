"""A thin pygame window for ``render_mode="human"`` (pygame, the ``render`` extra, is imported
only when a window opens)."""

import os
from types import ModuleType

import numpy as np

from pinball_env.extras import require


class Window:
    """A pygame window showing frames at a fixed rate (render_mode="human")."""

    @staticmethod
    def import_pygame() -> ModuleType:
        """pygame, or ``MissingDependency`` (Gymnasium's DependencyNotInstalled) with a one-line
        install hint that fits an installed package and a checkout (the ``render`` extra)."""
        os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
        pygame = require("pygame")
        return pygame

    def __init__(self, size: tuple[int, int], fps: float, title: str = "Pinball") -> None:
        pygame = self._pygame = self.import_pygame()
        self.size = (int(size[0]), int(size[1]))
        self.fps = float(fps)
        pygame.display.init()
        pygame.display.set_caption(title)
        self._screen = pygame.display.set_mode(self.size)
        self._clock = pygame.time.Clock()
        self._open = True

    def show(self, frame: np.ndarray) -> None:
        """Blit an (H, W, 3) uint8 frame (scaled to the window if needed), pump the event queue
        so the window stays responsive, and wait to hold ``fps``."""
        pygame = self._pygame
        surface = pygame.surfarray.make_surface(np.ascontiguousarray(frame.swapaxes(0, 1)))
        if surface.get_size() != self.size:
            surface = pygame.transform.scale(surface, self.size)
        self._screen.blit(surface, (0, 0))
        pygame.event.pump()
        pygame.display.flip()
        self._clock.tick(self.fps)

    def quit_requested(self) -> bool:
        """Whether the window was asked to close (a QUIT event waits in the queue)."""
        return bool(self._pygame.event.peek(self._pygame.QUIT))

    def close(self) -> None:
        """Close the window (safe to call twice)."""
        if self._open:
            self._pygame.display.quit()
            self._open = False
