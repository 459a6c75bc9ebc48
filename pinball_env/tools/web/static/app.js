// The page of python -m pinball_env.tools.serve: draws the game on a canvas from the table's
// geometry (the hello message, once) and each frame's state (frame messages), as
// pinball_env.render draws a frame; sends the buttons held, the commands and the replay's
// controls. Message formats: pinball_env/tools/web/stream.py and sessions.py.
"use strict";

// What the page shows, for people and for the browser tests: the last state drawn, counts.
const pinball = (window.pinball = {
  hello: null, timeline: null, drawn: null, framesDrawn: 0, errors: [], saved: null, dragging: false,
  received: { messages: 0, bytes: 0 }, send: null,
});

const socket = new WebSocket(`${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/ws`);
let pending = null; // the newest frame message not yet drawn
let views = []; // one per game: its canvas, its static layer, its scoreboard

pinball.send = (message) => {
  if (socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify(message));
};

socket.onopen = () => setStatus("connected");
// A server that closes after saying why (full, no game) keeps its reason in view.
socket.onclose = () => setStatus(pinball.hello || !pinball.errors.length
  ? "disconnected: reload the page to reconnect"
  : `error: ${pinball.errors[pinball.errors.length - 1]} (disconnected: reload to retry)`);
socket.onmessage = (event) => {
  pinball.received.messages += 1;
  pinball.received.bytes += event.data.length;
  const message = JSON.parse(event.data);
  if (message.type === "frame") pending = message;
  else if (message.type === "hello") start(message);
  else if (message.type === "timeline") showTimeline(message);
  else if (message.type === "saved") {
    pinball.saved = message;
    setStatus(`game saved: ${message.path} holds ${message.games}`);
  } else if (message.type === "error") {
    pinball.errors.push(message.message);
    setStatus(`error: ${message.message}`);
  }
};

function setStatus(text) {
  document.getElementById("status").textContent = text;
}

// --- drawing ---------------------------------------------------------------------------------

function rgb(colour) {
  return `rgb(${colour[0]},${colour[1]},${colour[2]})`;
}

// A view draws table `table` (its geometry) in its canvas: x right, y up the table [m].
function makeView(table, index) {
  const box = document.createElement("div");
  box.className = "game";
  const canvas = document.createElement("canvas");
  const scale = table.pixels_per_metre; // as render() frames
  canvas.width = Math.round(table.width * scale);
  canvas.height = Math.round(table.height * scale);
  canvas.id = `table${index}`;
  const board = document.createElement("div");
  board.className = "board";
  box.append(canvas, board);
  document.getElementById("games").append(box);
  const view = { table, canvas, board, scale, context: canvas.getContext("2d") };
  view.still = document.createElement("canvas");
  view.still.width = canvas.width;
  view.still.height = canvas.height;
  drawStatic(view, view.still.getContext("2d"));
  return view;
}

function toCanvas(view, context) {
  // World metres to pixels, y flipped: the same transform for every part.
  const s = view.scale;
  context.setTransform(s, 0, 0, -s, 0, view.table.height * s);
}

function line(view, context, x0, y0, x1, y1, half, colour) {
  context.strokeStyle = rgb(colour);
  context.lineWidth = 2 * Math.max(half, 0.6 / view.scale); // never thinner than a pixel
  context.lineCap = "round";
  context.beginPath();
  context.moveTo(x0, y0);
  context.lineTo(x1, y1);
  context.stroke();
}

function disc(context, x, y, radius, colour) {
  context.fillStyle = rgb(colour);
  context.beginPath();
  context.arc(x, y, radius, 0, 2 * Math.PI);
  context.fill();
}

function drawStatic(view, context) {
  const t = view.table, c = t.colours, w = t.half_widths;
  toCanvas(view, context);
  context.fillStyle = rgb(c.background);
  context.fillRect(-1, -1, t.width + 2, t.height + 2);
  const half = { wall: w.wall, one_sided: w.wall, kicker: w.wall, sensor: w.sensor,
                 drain: w.sensor, target: w.target };
  for (const [x0, y0, x1, y1, kind] of t.lines) {
    line(view, context, x0, y0, x1, y1, half[kind], c[kind === "target" ? "target" : kind]);
  }
  for (const [x, y, radius, kind] of t.discs) disc(context, x, y, radius, c[kind]);
}

function drawFlipper(context, [px, py, length, rb, rt], angle, colour) {
  // Two circles and the band between them, as the kernel's flipper shape.
  const dx = Math.cos(angle), dy = Math.sin(angle), tx = px + length * dx, ty = py + length * dy;
  context.fillStyle = rgb(colour);
  context.beginPath();
  context.moveTo(px - rb * dy, py + rb * dx);
  context.lineTo(tx - rt * dy, ty + rt * dx);
  context.lineTo(tx + rt * dy, ty - rt * dx);
  context.lineTo(px + rb * dy, py - rb * dx);
  context.fill();
  disc(context, px, py, rb, colour);
  disc(context, tx, ty, rt, colour);
}

function draw(view, state, paused) {
  const t = view.table, c = t.colours, w = t.half_widths, context = view.context;
  context.setTransform(1, 0, 0, 1, 0, 0);
  context.fillStyle = rgb(c.background);
  context.fillRect(0, 0, view.canvas.width, view.canvas.height);
  // The cabinet's shake moves the whole playfield (drawn `shake` times its size, as render()).
  const [ox, oy] = state.offset || [0, 0];
  context.drawImage(view.still, Math.round(ox * t.shake * view.scale), -Math.round(oy * t.shake * view.scale));
  toCanvas(view, context);
  context.translate(Math.round(ox * t.shake * view.scale) / view.scale, Math.round(oy * t.shake * view.scale) / view.scale);
  (state.targets || []).forEach((up, j) => {
    const [x0, y0, x1, y1] = t.drop_targets[j];
    line(view, context, x0, y0, x1, y1, up ? w.target : w.sensor, up ? c.target : c.target_down);
  });
  (state.spinners || []).forEach((angle, j) => {
    const [x0, y0, x1, y1, radius] = t.spinners[j];
    line(view, context, x0, y0, x1, y1, Math.abs(Math.sin(angle)) * radius, c.spinner);
  });
  const lit = [...(state.kickbacks || []), ...(state.lights || [])];
  lit.forEach((on, j) => disc(context, t.lamps[j][0], t.lamps[j][1], w.lamp, on ? c.light_on : c.light_off));
  state.flippers.forEach((angle, j) => drawFlipper(context, t.flippers[j], angle, c.flipper));
  let drop = 0; // the plunger's drawn pull: the ball waiting on it comes down with it
  const p = t.plunger;
  if (p && state.pull !== undefined) {
    drop = Math.min(Math.max(state.pull, 0), p.stroke) * p.pull_scale;
    const tip = p.y - t.ball_radius - drop;
    line(view, context, p.x, tip - p.bar, p.x, -0.01, p.rod, c.plunger);
    line(view, context, p.x - p.reach, tip - p.bar, p.x + p.reach, tip - p.bar, p.bar, c.plunger);
  }
  state.balls.forEach(([x, y], j) => {
    disc(context, x, j === 0 && state.on_plunger ? y - drop : y, t.ball_radius, c.ball);
  });
  drawBoard(view, state, paused);
}

function drawBoard(view, state, paused) {
  const rows = [["score", state.score], ["balls", state.balls_left]];
  if (state.trough !== undefined) rows.push(["trough", state.trough]);
  if (state.bonus !== undefined) rows.push(["bonus", `${state.bonus} ×${state.multiplier}`]);
  if (state.seed !== undefined) rows.push(["seed", state.seed]);
  let html = rows.map(([k, v]) => `<div class="label">${k}</div><div class="value">${v}</div>`).join("");
  if (state.tilted) html += `<div class="value alert">TILT</div>`;
  else if (state.warnings) html += `<div class="value alert">WARNING ${state.warnings}</div>`;
  if (state.over) html += `<div class="value alert">GAME OVER</div>`;
  else if (paused) html += `<div class="value alert">PAUSED</div>`;
  if (html !== view.lastBoard) view.board.innerHTML = view.lastBoard = html;
}

let seekTo = null; // the timeline's frame to seek, sent once a frame however fast it is dragged

function frameLoop() {
  if (seekTo !== null) {
    pinball.send({ type: "seek", frame: seekTo });
    seekTo = null;
  }
  if (pending) {
    const message = pending;
    pending = null;
    message.games.forEach((state, j) => views[j] && draw(views[j], state, message.paused));
    if (message.replay) showPosition(message.replay);
    if (views.length) {
      pinball.drawn = message;
      pinball.framesDrawn += 1;
    }
  }
  requestAnimationFrame(frameLoop);
}
requestAnimationFrame(frameLoop);

// --- playing: keys and touch buttons -----------------------------------------------------------

const held = new Set();

function sendHeld() {
  pinball.send({ type: "buttons", held: [...held] });
}

function press(button, down) {
  if (down === held.has(button)) return;
  if (down) held.add(button);
  else held.delete(button);
  sendHeld();
}

function start(hello) {
  pinball.hello = hello;
  views.forEach((view) => view.canvas.parentElement.remove());
  views = hello.tables.map(makeView);
  setStatus(`${hello.mode}: ${hello.env_id}${hello.player ? ` (${hello.player})` : ""}`);
  const keys = hello.keys || {};
  const help = {};
  for (const [code, name] of Object.entries(keys)) (help[name] = help[name] || []).push(code);
  document.getElementById("help").textContent = hello.mode === "replay"
    ? "keys: Space play / pause, Left / Right arrow a frame back / on"
    : "keys: " + Object.entries(help).map(([name, codes]) => `${name.replace("_", " ")}: ${codes.join(" / ")}`).join(", ");
  if (hello.mode === "replay") startReplay(hello);
  else startTouch(hello);
  document.addEventListener("keydown", (event) => key(event, true));
  document.addEventListener("keyup", (event) => key(event, false));
  window.addEventListener("blur", () => { held.clear(); if (hello.mode === "play") sendHeld(); });
}

function key(event, down) {
  const hello = pinball.hello;
  if (hello.mode === "replay") return replayKey(event, down);
  const name = hello.keys[event.code];
  if (name === undefined) return;
  event.preventDefault();
  if (hello.buttons && hello.buttons.includes(name)) press(name, down);
  else if (down && !event.repeat) pinball.send({ type: "command", command: name });
}

function startTouch(hello) {
  const touch = document.getElementById("touch");
  touch.hidden = false;
  for (const name of [...(hello.buttons || []), "pause", "restart"]) {
    const button = document.createElement("button");
    button.textContent = name.replace("_", " ");
    button.dataset.name = name;
    touch.append(button);
    if (name === "pause" || name === "restart") {
      button.addEventListener("click", () => pinball.send({ type: "command", command: name }));
      continue;
    }
    const set = (down) => (event) => {
      event.preventDefault();
      button.classList.toggle("held", down);
      press(name, down);
    };
    button.addEventListener("pointerdown", set(true));
    for (const up of ["pointerup", "pointerleave", "pointercancel"]) button.addEventListener(up, set(false));
  }
}

// --- replay: the timeline ----------------------------------------------------------------------

function startReplay(hello) {
  document.getElementById("replay").hidden = false;
  const games = document.getElementById("game");
  hello.games.forEach((game, j) => games.add(new Option(`${j + 1}: seed ${game.seed}, ${game.score}`, j)));
  games.onchange = () => pinball.send({ type: "game", game: Number(games.value) });
  document.getElementById("play").onclick = () => pinball.send({ type: "command", command: "pause" });
  document.getElementById("back").onclick = () => pinball.send({ type: "step", frames: -1 });
  document.getElementById("next").onclick = () => pinball.send({ type: "step", frames: 1 });
  const speed = document.getElementById("speed");
  speed.onchange = () => pinball.send({ type: "speed", speed: Number(speed.value) });
  const timeline = document.getElementById("timeline");
  timeline.oninput = () => { seekTo = Number(timeline.value); };
  // While the slider is held it is the page's to move; once let go, playback moves it again
  // (focus stays on a clicked slider, so focus cannot say which).
  timeline.addEventListener("pointerdown", () => { pinball.dragging = true; });
  window.addEventListener("pointerup", () => { pinball.dragging = false; });
}

function replayKey(event, down) {
  if (!down) return;
  const steps = { ArrowLeft: -1, ArrowRight: 1 };
  if (event.code === "Space") pinball.send({ type: "command", command: "pause" });
  else if (event.code in steps) pinball.send({ type: "step", frames: steps[event.code] });
  else return;
  event.preventDefault();
}

function showTimeline(timeline) {
  pinball.timeline = timeline;
  const slider = document.getElementById("timeline");
  slider.max = timeline.frames;
  // The score at every frame, as a curve under the slider.
  const curve = document.getElementById("curve");
  curve.width = curve.clientWidth || 600;
  const context = curve.getContext("2d"), scores = timeline.scores;
  const top = Math.max(1, scores[scores.length - 1]);
  context.clearRect(0, 0, curve.width, curve.height);
  context.strokeStyle = "#fac33c";
  context.beginPath();
  scores.forEach((score, k) => {
    const x = (k / Math.max(1, scores.length - 1)) * curve.width, y = curve.height * (1 - score / top);
    if (k === 0) context.moveTo(x, y);
    else context.lineTo(x, y);
  });
  context.stroke();
}

function showPosition(replay) {
  const slider = document.getElementById("timeline");
  if (!pinball.dragging) slider.value = replay.frame;
  document.getElementById("play").textContent = replay.playing ? "pause" : "play";
  const scores = pinball.timeline ? pinball.timeline.scores : [];
  document.getElementById("position").textContent =
    `frame ${replay.frame} / ${replay.frames}, score ${scores[replay.frame] ?? ""}` +
    (pinball.timeline ? ` (recorded ${pinball.timeline.score}, ${pinball.timeline.end})` : "");
}
