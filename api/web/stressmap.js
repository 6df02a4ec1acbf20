// Stress on the drawing (scene.js): a frame's `stresses` ({element: stress at each point of its
// deformed centre line}, the drawing's stress unit; POST /v1/drawings) drawn as coloured
// segments on a perceptually even scale (viridis) from 0 to the frame's largest stress, or to
// the smallest material limit when that is larger; a segment above its element's limit
// (`stress_limit`) drawn in the warning style; a colour bar with its scale, unit and the limit.

import { display } from "./display.js";
import { formatNumber } from "./plot.js";

const SVG = "http://www.w3.org/2000/svg";
// viridis (van der Walt and Smith), sampled at nine even steps: even in lightness, readable in grey
const VIRIDIS = ["#440154", "#472d7b", "#3b528b", "#2c728e", "#21918c", "#28ae80", "#5ec962", "#addc30", "#fde725"];
export const OVER_LIMIT = "#d4002a";

function node(name, attributes = {}, parent = null) {
  const element = document.createElementNS(SVG, name);
  for (const [key, value] of Object.entries(attributes)) element.setAttribute(key, value);
  if (parent) parent.append(element);
  return element;
}

function rgb(hex) {
  return [1, 3, 5].map((k) => parseInt(hex.slice(k, k + 2), 16));
}

// The colour of `t` in [0, 1] (clamped), interpolated between the samples.
export function viridis(t) {
  const x = Math.max(0, Math.min(1, Number.isFinite(t) ? t : 0)) * (VIRIDIS.length - 1);
  const k = Math.min(VIRIDIS.length - 2, Math.floor(x)), f = x - k;
  const [a, b] = [rgb(VIRIDIS[k]), rgb(VIRIDIS[k + 1])];
  return `rgb(${a.map((v, i) => Math.round(v + f * (b[i] - v))).join(",")})`;
}

// {top, limit, unit, shown} of a frame's stresses, or null when it has none: the scale's end is
// the largest stress, or the smallest limit of a stressed element when that is larger; `shown`
// is the display its labels use (display.js: MPa where the document's stresses are 0.19 GPa, as
// the tables show them); the data attributes keep the document's unit.
export function stressScale(drawing, frame) {
  const stresses = frame && frame.stresses;
  if (!stresses || !Object.keys(stresses).length) return null;
  const largest = Math.max(0, ...Object.values(stresses).flat().filter(Number.isFinite));
  const limits = drawing.elements.filter((e) => stresses[e.name] && e.stress_limit > 0).map((e) => e.stress_limit);
  const limit = limits.length ? Math.min(...limits) : null;
  const unit = (drawing.units && drawing.units.stress) || "";
  const top = Math.max(largest, limit || 0) || 1;
  return { top, largest, limit, unit, shown: display(unit, [top]) };
}

// One element's deformed centre line as segments coloured by stress; each segment takes the
// larger of its two ends' stresses (its `data-stress`). Over them, the whole line as one clear
// path (data-element, as an element without stresses is drawn): what a pointer points at, for
// the tooltip naming the largest stress and for picking (pickers.js). Returns the group.
export function drawStressedElement(layer, element, points, stresses, scale, pathOf) {
  const largest = Math.max(...stresses);
  const limit = element.stress_limit > 0 ? element.stress_limit : null;
  const group = node("g", { "data-stressed": element.name, "data-stress-max": String(largest), class: "stressed" }, layer);
  for (let i = 0; i + 1 < points.length; i++) {
    const stress = Math.max(stresses[i], stresses[i + 1]);
    const over = limit !== null && stress > limit;
    node("path", { d: pathOf([points[i], points[i + 1]]), fill: "none", "stroke-linecap": "round", "data-stress": String(stress),
                   stroke: over ? OVER_LIMIT : viridis(stress / scale.top), "stroke-width": over ? "4.4" : "3.2",
                   ...(over ? { "stroke-dasharray": "5 2.5", class: "over-limit" } : {}) }, group);
  }
  const against = limit !== null ? ` (limit ${scale.shown.text(limit, true)}${largest > limit ? ": exceeded" : ""})` : "";
  const line = node("path", { d: pathOf(points), fill: "none", stroke: "transparent", "stroke-width": "9", "stroke-linecap": "round",
                              "pointer-events": "stroke", "data-element": element.name }, group);
  node("title", {}, line).textContent = `element ${element.name} (${element.from} to ${element.to}): largest stress ${scale.shown.text(largest, true)}${against}`;
  return group;
}

// The colour bar at the plot's top right corner (`box`: {right, top} in SVG units, `grow` its
// size where the drawing is shown small, a phone's): 0 to the scale's end with ticks, the unit,
// the limit marked and the largest stress named.
export function drawColourBar(svg, scale, box) {
  const grow = box.grow || 1;
  const bar = node("g", { class: "colour-bar", "data-top": String(scale.top), "font-size": "11", fill: "#1d2430",
                          transform: `translate(${box.right} ${box.top}) scale(${grow}) translate(${-box.right} ${-box.top})` }, svg);
  const width = 14, height = 150, x = box.right - 74, y = box.top + 52; // below a frame's label
  node("rect", { x: x - 46, y: y - 26, width: 116, height: height + 56, fill: "#fff", "fill-opacity": "0.86", stroke: "#d5dae2", rx: 3 }, bar);
  node("text", { x: x + width / 2, y: y - 10, "text-anchor": "middle", class: "colour-bar-title", "font-weight": "600" }, bar).textContent = `stress [${scale.shown.unit}]`;
  const gradient = node("linearGradient", { id: "stress-scale", x1: "0", y1: "1", x2: "0", y2: "0" }, node("defs", {}, bar));
  VIRIDIS.forEach((colour, k) => node("stop", { offset: String(k / (VIRIDIS.length - 1)), "stop-color": colour }, gradient));
  node("rect", { x, y, width, height, fill: "url(#stress-scale)", stroke: "#5b6575", "stroke-width": "0.6" }, bar);
  for (const k of [0, 0.25, 0.5, 0.75, 1]) {
    const ty = y + height * (1 - k);
    node("line", { x1: x + width, x2: x + width + 4, y1: ty, y2: ty, stroke: "#5b6575" }, bar);
    node("text", { x: x + width + 7, y: ty + 4, class: "colour-bar-tick" }, bar).textContent = formatNumber(Number(scale.shown.value(scale.top * k).toPrecision(3)));
  }
  if (scale.limit !== null) {
    const ly = y + height * (1 - scale.limit / scale.top);
    const mark = node("g", { class: "limit-mark", "data-limit": String(scale.limit) }, bar);
    node("line", { x1: x - 6, x2: x + width + 2, y1: ly, y2: ly, stroke: OVER_LIMIT, "stroke-width": "2.2" }, mark);
    node("text", { x: x - 8, y: ly + 4, "text-anchor": "end", fill: OVER_LIMIT, "font-weight": "600" }, mark).textContent = "limit";
    node("title", {}, mark).textContent = `material limit ${scale.shown.text(scale.limit, true)}`;
  }
  node("text", { x: x - 40, y: y + height + 22, class: "colour-bar-largest" }, bar).textContent = `max ${scale.shown.text(scale.largest)}`;
  return bar;
}
