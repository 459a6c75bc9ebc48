"""The browser page end to end, in headless Chromium (the system's ``chromium``, driven by
Playwright): the page loads and draws, a key or a touch button lifts a flipper in the drawn
state (the page keeps the last state it drew on ``window.pinball``), a recording replays to its
recorded score, two pages at once. Skipped, saying which, without chromium or Playwright.

``python tests/tools/test_serve_browser.py docs/browser.png`` writes the docs' screenshot.
"""

import json
import shutil
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import gymnasium as gym
import pytest

from pinball_env.recording import load_recording
from pinball_env.tools import serve
from pinball_env.tools.web.sessions import PlaySession, Recorder, ReplayIndex, ReplaySession

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="no chromium on this machine")
playwright_api = pytest.importorskip("playwright.sync_api", reason="playwright is not installed")
pytest.importorskip("uvicorn", reason="the web extra is not installed")

LEFT, RIGHT = 0, 1  # the flippers' indices in a drawn state
TIMEOUT = 60_000  # [ms] for the page to show what is waited for (a loaded machine is slow)

# The frames the page drew over three seconds of its own clock (requestAnimationFrame).
MEASURE_FPS = """async () => {
  const start = window.pinball.framesDrawn, t0 = performance.now();
  await new Promise((done) => setTimeout(done, 3000));
  return (window.pinball.framesDrawn - start) / ((performance.now() - t0) / 1000);
}"""
# How many of the canvas's pixels differ from the background: the drawn table.
DRAWN_PIXELS = """() => {
  const canvas = document.getElementById("table0");
  const pixels = canvas.getContext("2d").getImageData(0, 0, canvas.width, canvas.height).data;
  const background = window.pinball.hello.tables[0].colours.background;
  let drawn = 0;
  for (let i = 0; i < pixels.length; i += 4) {
    if (Math.abs(pixels[i] - background[0]) + Math.abs(pixels[i + 1] - background[1]) > 30) drawn++;
  }
  return drawn;
}"""


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    with playwright_api.sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        yield browser
        browser.close()


def open_page(browser: Any, url: str) -> Any:
    page = browser.new_page(viewport={"width": 720, "height": 900})
    page.goto(url)
    page.wait_for_function("window.pinball.framesDrawn > 10", timeout=TIMEOUT)
    return page


def drawn(page: Any, path: str) -> Any:
    return page.evaluate(f"window.pinball.drawn.{path}")


def test_the_page_loads_and_draws_at_the_games_frame_rate(browser, serving):
    app = serve.make_app(lambda: PlaySession("Pinball-v3", seed=1))
    with serving(app) as url:
        page = open_page(browser, url)
        assert page.evaluate("window.pinball.hello.mode") == "play"
        assert page.evaluate(DRAWN_PIXELS) > 5000  # walls, posts, flippers, ball: not blank
        fps = page.evaluate(MEASURE_FPS)
        received = page.evaluate("window.pinball.received")
        print(f"\nthe page drew {fps:.1f} frames per second; received {received}")
        assert fps > 0 and page.evaluate("window.pinball.errors") == []
        page.close()


def test_a_key_or_a_touch_button_lifts_a_flipper(browser, serving):
    app = serve.make_app(lambda: PlaySession("Pinball-v1", seed=2))
    with serving(app) as url:
        page = open_page(browser, url)
        rest = drawn(page, f"games[0].flippers[{LEFT}]")
        page.keyboard.down("z")
        page.wait_for_function(
            f"window.pinball.drawn.games[0].flippers[{LEFT}] > {rest}", timeout=TIMEOUT
        )
        page.keyboard.up("z")
        page.wait_for_function(
            f"window.pinball.drawn.games[0].flippers[{LEFT}] === {rest}", timeout=TIMEOUT
        )
        # P pauses: the drawn frame stands still, the board says so; P again plays on.
        page.keyboard.press("p")
        page.wait_for_function("window.pinball.drawn.paused === true", timeout=TIMEOUT)
        assert "PAUSED" in page.inner_text(".board")
        page.keyboard.press("p")
        page.wait_for_function("window.pinball.drawn.paused === false", timeout=TIMEOUT)
        # The right flipper from its touch button (angles turn the other way).
        right_rest = drawn(page, f"games[0].flippers[{RIGHT}]")
        button = page.locator('#touch button[data-name="right"]')
        button.dispatch_event("pointerdown")
        page.wait_for_function(
            f"window.pinball.drawn.games[0].flippers[{RIGHT}] < {right_rest}", timeout=TIMEOUT
        )
        button.dispatch_event("pointerup")
        page.close()


def test_a_recording_replays_to_its_recorded_score(browser, serving, tmp_path):
    path = tmp_path / "games.json"
    recorder = Recorder(path, gym.make("Pinball-v1"), "Pinball-v1", {"table": "classic_v1"})
    session = PlaySession("Pinball-v1", {"table": "classic_v1"}, seed=3, recorder=recorder)
    for tick in range(600):
        held = ["plunger"] if tick < 40 else ["left", "right"] if tick % 25 < 4 else []
        session.receive(json.dumps({"type": "buttons", "held": held}))
        session.tick()
    session.close()
    (game,) = load_recording(path).games
    index = ReplayIndex(load_recording(path))
    with serving(serve.make_app(lambda: ReplaySession(index))) as url:
        page = open_page(browser, url)
        assert page.evaluate("window.pinball.timeline.frames") == game.frames
        page.select_option("#speed", "16")
        page.click("#play")
        page.wait_for_function(
            f"window.pinball.drawn.replay.frame === {game.frames}", timeout=TIMEOUT
        )
        assert drawn(page, "games[0].score") == game.score > 0
        assert f"score {game.score}" in page.inner_text("#position")
        # Scrubbed back on the timeline: the score there, as the timeline says.
        middle = game.frames // 2
        page.evaluate(
            f"""() => {{
            const slider = document.getElementById("timeline");
            slider.value = {middle};
            slider.dispatchEvent(new Event("input"));
        }}"""
        )
        page.wait_for_function(f"window.pinball.drawn.replay.frame === {middle}", timeout=TIMEOUT)
        scores = page.evaluate("window.pinball.timeline.scores")
        assert drawn(page, "games[0].score") == scores[middle]
        # A frame on, from the page's button.
        page.click("#next")
        page.wait_for_function(
            f"window.pinball.drawn.replay.frame === {middle + 1}", timeout=TIMEOUT
        )
        # Playing, a click on the slider seeks there; then playback moves the slider on again
        # (the slider keeps the focus: the page used to stop moving it).
        page.select_option("#speed", "1")
        page.click("#play")
        page.wait_for_function("window.pinball.drawn.replay.playing", timeout=TIMEOUT)
        page.click("#timeline", position={"x": 5, "y": 5})  # near the start
        page.wait_for_function("window.pinball.drawn.replay.frame < 60", timeout=TIMEOUT)
        assert page.evaluate("document.activeElement.id") == "timeline"
        page.wait_for_function(
            "Number(document.getElementById('timeline').value) > 90", timeout=TIMEOUT
        )
        page.close()


def test_two_pages_at_once_each_play_their_own_game(browser, serving):
    app = serve.make_app(lambda: PlaySession("Pinball-v0", seed=4))
    with serving(app) as url:
        first, second = open_page(browser, url), open_page(browser, url)
        rest = drawn(second, f"games[0].flippers[{LEFT}]")
        first.keyboard.down("z")
        first.wait_for_function(
            f"window.pinball.drawn.games[0].flippers[{LEFT}] > {rest}", timeout=TIMEOUT
        )
        seen = second.evaluate("window.pinball.framesDrawn")
        second.wait_for_function(f"window.pinball.framesDrawn > {seen + 30}", timeout=TIMEOUT)
        assert drawn(second, f"games[0].flippers[{LEFT}]") == rest  # not the first page's keys
        first.keyboard.up("z")
        first.close()
        second.close()


CANVAS_BOX = """() => {
  const r = document.getElementById("table0").getBoundingClientRect();
  return [r.left, r.right, r.top, r.bottom];
}"""


@pytest.mark.parametrize(("width", "height"), [(390, 844), (1600, 900)])
def test_the_table_fits_the_screen_and_stays_put_when_an_alert_appears(
    browser, serving, width, height
):
    """A phone's and a wide screen's page: the whole table in view (nothing cut off at the
    left, no sideways scroll), drawn at its own aspect ratio; WARNING and GAME OVER appearing
    on the board do not move it."""
    app = serve.make_app(lambda: PlaySession("Pinball-v1", seed=2))
    with serving(app) as url:
        page = browser.new_page(viewport={"width": width, "height": height})
        page.goto(url)
        page.wait_for_function("window.pinball.framesDrawn > 10", timeout=TIMEOUT)
        left, right, top, bottom = box = page.evaluate(CANVAS_BOX)
        assert 0 <= left < right <= width, box
        assert page.evaluate("document.documentElement.scrollWidth") <= width
        pixels = page.evaluate("[table0.width, table0.height]")
        assert (bottom - top) / (right - left) == pytest.approx(pixels[1] / pixels[0], rel=0.02)
        # The longest alerts on the board (drawn as a frame draws them), measured at once.
        alerted = page.evaluate(f"""() => {{
            const state = {{...window.pinball.drawn.games[0], warnings: 3, over: true}};
            drawBoard(views[0], state, false);
            return ({CANVAS_BOX})();
        }}""")
        assert alerted == box
        page.close()


def test_a_full_server_says_so_and_keeps_saying_it(browser, serving):
    """The server's "full" message stays in view after it closes the socket (the close handler
    used to overwrite it with "disconnected")."""
    app = serve.make_app(lambda: PlaySession("Pinball-v0", seed=4), max_viewers=1)
    with serving(app) as url:
        first = open_page(browser, url)
        first.wait_for_function("window.pinball.hello !== null", timeout=TIMEOUT)
        second = browser.new_page(viewport={"width": 720, "height": 900})
        second.goto(url)
        second.wait_for_function(
            "document.getElementById('status').textContent.includes('disconnected')",
            timeout=TIMEOUT,
        )
        status = second.evaluate("document.getElementById('status').textContent")
        assert status.startswith("error: full: 1 pages at most"), status
        first.close()
        second.close()


def screenshot(path: Path) -> None:
    """The docs' picture: a game of Pinball-v3 watched, the heuristic playing, some seconds in."""
    from tests.tools.conftest import running

    args = serve.parser().parse_args(["--watch", "heuristic", "--env", "Pinball-v3"])
    factory, title = serve.session_factory(args)
    with (
        playwright_api.sync_playwright() as playwright,
        running(serve.make_app(factory, title=title)) as url,
    ):
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        page = browser.new_page(viewport={"width": 560, "height": 700})
        page.goto(url)
        page.wait_for_function("window.pinball.framesDrawn > 600", timeout=TIMEOUT)
        page.screenshot(path=str(path))
        browser.close()
    print(f"wrote {path}")


if __name__ == "__main__":
    screenshot(Path(sys.argv[1] if len(sys.argv) > 1 else "docs/browser.png"))
