// The animation of a result's frames (simulation states, contact path states): a slider
// (keyboard: arrows, Home, End), Play/Pause at a speed (a simulation in real time, or slower or
// faster; any frames one by one), and the frame's label (time or field value).

import { drawScene, sceneBounds } from "./scene.js";

const $ = (id) => document.getElementById(id);
const PLAY_SECONDS = 8; // a whole animation of frames not in time (states of a sweep, a mode's swing)
const FRAMES_PER_SECOND = 10; // playing frame by frame
const BOUND_SAMPLES = 200; // frames looked at for the drawing's fixed extent

let current = { drawing: null, frames: [], bounds: null, playing: false };

function showFrame(index) {
  const { drawing, frames, bounds } = current;
  if (!drawing || !frames.length) return;
  const k = Math.max(0, Math.min(frames.length - 1, index));
  $("frame").value = String(k);
  drawScene($("drawing"), drawing, frames[k], bounds);
  $("frame-label").textContent = `${k + 1} / ${frames.length}: ${frames[k].label || ""}`;
}

function stop() {
  current.playing = false;
  $("play").textContent = "Play";
  $("play").setAttribute("aria-pressed", "false");
}

// The frame to show `elapsed` seconds after frame `first` started playing: frames in time (a
// simulation's) at the speed chosen (1: real time); others, or "frames", at FRAMES_PER_SECOND,
// else the whole animation in PLAY_SECONDS.
function frameAfter(frames, first, elapsed) {
  const speed = $("speed").value;
  const timed = frames.every((f) => typeof f.time === "number");
  if (timed && speed !== "frames") {
    const t = frames[first].time + elapsed * Number(speed);
    let k = first;
    while (k < frames.length - 1 && frames[k + 1].time <= t) k += 1;
    return k;
  }
  const rate = speed === "frames" ? FRAMES_PER_SECOND : frames.length / PLAY_SECONDS;
  return first + Math.floor(elapsed * rate);
}

function play() {
  const { frames } = current;
  if (frames.length < 2) return;
  current.playing = true;
  $("play").textContent = "Pause";
  $("play").setAttribute("aria-pressed", "true");
  let start = null;
  const first = Number($("frame").value) >= frames.length - 1 ? 0 : Number($("frame").value);
  const tick = (now) => {
    if (!current.playing) return;
    if (start === null) start = now;
    const k = frameAfter(frames, first, (now - start) / 1000);
    showFrame(k);
    if (k >= frames.length - 1) { stop(); return; }
    requestAnimationFrame(tick);
  };
  requestAnimationFrame(tick);
}

// The frames of a result, shown at frame `open` (default the last: where a simulation or a
// path ends; a modes' animation opens on its first mode).
export function setFrames(drawing, frames, open = frames.length - 1) {
  stop();
  const every = Math.max(1, Math.floor(frames.length / BOUND_SAMPLES));
  const sampled = frames.filter((_, i) => i % every === 0 || i === frames.length - 1);
  current = { drawing, frames, bounds: frames.length ? sceneBounds(drawing, [null, ...sampled]) : null, playing: false };
  $("animation").hidden = frames.length < 2;
  $("frame").max = String(Math.max(0, frames.length - 1));
  if (frames.length) showFrame(open);
  else $("frame-label").textContent = "";
}

// Frames to show and play at once (a mode picked from its table).
export function playFrames(drawing, frames) {
  setFrames(drawing, frames);
  showFrame(0);
  play();
}

export function clearFrames() {
  setFrames(null, []);
}

export function wireAnimation() {
  $("frame").addEventListener("input", () => { stop(); showFrame(Number($("frame").value)); });
  $("play").addEventListener("click", () => (current.playing ? stop() : play()));
}
