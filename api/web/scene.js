// The mechanism drawn to scale in SVG: equal axes in the document's length unit, ticks and
// axis labels with the unit; undeformed dashed and grey under the deformed state of a frame.
// A frame is {elements: {name: points}, poses: {body: [dx, dy, rotation]}, about, overlay}:
// bodies' outlines, skeletons, joints, points and loads follow their body's pose. A frame's
// `stresses` colour its elements (stressmap.js); the view zooms and pans (zoom.js).

import { formatNumber, niceTicks } from "./plot.js";
import { drawColourBar, drawStressedElement, stressScale } from "./stressmap.js";
import { drawn, viewedBounds } from "./zoom.js";

const SVG = "http://www.w3.org/2000/svg";
const WIDTH = 820, HEIGHT = 560, MARGIN = { left: 64, right: 16, top: 16, bottom: 46 };
const ARROW_SPAN = 0.18; // the largest force's arrow, as a fraction of the drawing's span
const COLORS = { undeformed: "#9aa3ad", element: "#0b62a4", body: "#1d2430", load: "#1b7a32",
                 point: "#b3261e", object: "#c46a00", force: "#7b2cbf" };

function node(name, attributes = {}, parent = null) {
  const element = document.createElementNS(SVG, name);
  for (const [key, value] of Object.entries(attributes)) element.setAttribute(key, value);
  if (parent) parent.append(element);
  return element;
}

// A point of body `body` moved by the frame's pose of that body.
export function placed(drawing, frame, body, point) {
  const pose = frame && frame.poses && body ? frame.poses[body] : null;
  if (!pose) return point;
  const about = frame.about === "centre" ? drawing.bodies[body].centre : drawing.bodies[body].reference;
  const [dx, dy, turn] = pose, c = Math.cos(turn), s = Math.sin(turn);
  const u = point[0] - about[0], v = point[1] - about[1];
  return [about[0] + dx + c * u - s * v, about[1] + dy + s * u + c * v];
}

// Poses of the free bodies where the elements' given centre lines end (translations: the
// bodies of a link network are its joints), for states given by centre lines alone.
export function posesAtElementEnds(drawing, elements) {
  const poses = {};
  for (const element of drawing.elements) {
    const now = elements[element.name];
    if (!now) continue;
    for (const [body, undeformed, deformed] of [[element.from, element.points[0], now[0]], [element.to, element.points.at(-1), now.at(-1)]]) {
      if (drawing.bodies[body] && !drawing.bodies[body].fixed && !poses[body]) {
        const ref = drawing.bodies[body].reference;
        if (Math.hypot(undeformed[0] - ref[0], undeformed[1] - ref[1]) < 1e-9 * (1 + Math.hypot(...ref))) poses[body] = [deformed[0] - ref[0], deformed[1] - ref[1], 0];
      }
    }
  }
  return poses;
}

// [xmin, ymin, xmax, ymax] of everything drawn in the frames (undeformed included).
export function sceneBounds(drawing, frames = [null]) {
  const box = [Infinity, Infinity, -Infinity, -Infinity];
  const add = (p) => { if (p && Number.isFinite(p[0]) && Number.isFinite(p[1])) { box[0] = Math.min(box[0], p[0]); box[1] = Math.min(box[1], p[1]); box[2] = Math.max(box[2], p[0]); box[3] = Math.max(box[3], p[1]); } };
  for (const frame of frames) {
    for (const [name, body] of Object.entries(drawing.bodies)) add(placed(drawing, frame, name, body.reference));
    for (const element of drawing.elements) ((frame && frame.elements && frame.elements[element.name]) || element.points).forEach(add);
    for (const outline of drawing.outlines) if (outline.closed) outline.points.forEach((p) => add(placed(drawing, frame, outline.body, p)));
    for (const point of drawing.points) add(placed(drawing, frame, point.body, point.point));
    for (const line of (frame && frame.overlay && frame.overlay.lines) || []) if (line.closed !== false || line.bounded) line.points.forEach(add);
  }
  if (!Number.isFinite(box[0])) return [-1, -1, 1, 1];
  const span = Math.max(box[2] - box[0], box[3] - box[1]) || 1;
  const pad = 0.12 * span;
  return [box[0] - pad, box[1] - pad, box[2] + pad, box[3] + pad];
}

function transform(bounds) {
  const width = WIDTH - MARGIN.left - MARGIN.right, height = HEIGHT - MARGIN.top - MARGIN.bottom;
  const scale = Math.min(width / (bounds[2] - bounds[0]), height / (bounds[3] - bounds[1]));
  const cx = (bounds[0] + bounds[2]) / 2, cy = (bounds[1] + bounds[3]) / 2;
  const x0 = MARGIN.left + width / 2, y0 = MARGIN.top + height / 2;
  const map = (p) => [x0 + (p[0] - cx) * scale, y0 - (p[1] - cy) * scale];
  const unmap = (q) => [cx + (q[0] - x0) / scale, cy - (q[1] - y0) / scale];
  const visible = [cx - width / 2 / scale, cy - height / 2 / scale, cx + width / 2 / scale, cy + height / 2 / scale];
  return { map, unmap, scale, visible };
}

function pathOf(points, map, closed = false) {
  const parts = points.map((p, i) => { const [x, y] = map(p); return `${i ? "L" : "M"}${x.toFixed(2)},${y.toFixed(2)}`; });
  return parts.join("") + (closed ? "Z" : "");
}

function drawAxes(svg, view, unit) {
  const axes = node("g", { "font-size": "11", fill: "#5b6575", "font-family": "system-ui, sans-serif" }, svg);
  const [x0, y0, x1, y1] = view.visible;
  const step = (ticks) => (ticks.length > 1 ? ticks[1] - ticks[0] : 1);
  const xs = niceTicks(x0, x1, 8), ys = niceTicks(y0, y1, 6);
  const top = MARGIN.top, bottom = HEIGHT - MARGIN.bottom, left = MARGIN.left, right = WIDTH - MARGIN.right;
  node("rect", { x: left, y: top, width: right - left, height: bottom - top, fill: "none", stroke: "#d5dae2" }, axes);
  for (const x of xs) {
    const [px] = view.map([x, 0]);
    if (px < left - 0.5 || px > right + 0.5) continue;
    node("line", { x1: px, x2: px, y1: top, y2: bottom, stroke: "#eef0f3" }, axes);
    node("text", { x: px, y: bottom + 15, "text-anchor": "middle" }, axes).textContent = formatNumber(Math.abs(x) < step(xs) * 1e-9 ? 0 : x);
  }
  for (const y of ys) {
    const [, py] = view.map([0, y]);
    if (py < top - 0.5 || py > bottom + 0.5) continue;
    node("line", { x1: left, x2: right, y1: py, y2: py, stroke: "#eef0f3" }, axes);
    node("text", { x: left - 6, y: py + 4, "text-anchor": "end" }, axes).textContent = formatNumber(Math.abs(y) < step(ys) * 1e-9 ? 0 : y);
  }
  node("text", { x: (left + right) / 2, y: HEIGHT - 8, "text-anchor": "middle", class: "axis-label" }, axes).textContent = `x [${unit}]`;
  const label = node("text", { x: 14, y: (top + bottom) / 2, "text-anchor": "middle", class: "axis-label",
                               transform: `rotate(-90 14 ${(top + bottom) / 2})` }, axes);
  label.textContent = `y [${unit}]`;
}

function drawOutlines(layer, drawing, frame, view) {
  const hidden = new Set((frame && frame.overlay && frame.overlay.replaces) || []);
  for (const outline of drawing.outlines) {
    if (hidden.has(outline.name)) continue;
    const points = outline.points.map((p) => placed(drawing, frame, outline.body, p));
    const solid = outline.solid && outline.closed;
    node("path", { d: pathOf(points, view.map, outline.closed), fill: solid ? "#f6e3cc" : "none", "fill-opacity": "0.7",
                   stroke: COLORS.object, "stroke-width": "1.4", "stroke-dasharray": outline.solid ? "" : "5 3",
                   "data-outline": outline.name }, layer);
  }
}

// An element whose shape the frame does not give (a rigid-body simulation): each point moved
// by its two bodies' motions, weighted by how far along the element it lies.
function blended(drawing, frame, element) {
  const last = element.points.length - 1 || 1;
  return element.points.map((p, i) => {
    const a = placed(drawing, frame, element.from, p), b = placed(drawing, frame, element.to, p), t = i / last;
    return [(1 - t) * a[0] + t * b[0], (1 - t) * a[1] + t * b[1]];
  });
}

function drawElements(layer, drawing, frame, view, scale) {
  for (const element of drawing.elements) {
    node("path", { d: pathOf(element.points, view.map), fill: "none", stroke: COLORS.undeformed, "stroke-width": "1",
                   "stroke-dasharray": "4 3" }, layer);
    if (frame && frame.hideElements) continue; // the frame's overlay draws them
    const shape = frame && frame.elements && frame.elements[element.name];
    const stresses = scale && shape && frame.stresses[element.name];
    if (stresses && stresses.length === shape.length && shape.length > 1) {
      drawStressedElement(layer, element, shape, stresses, scale, (points) => pathOf(points, view.map));
      continue;
    }
    const now = shape || (frame && frame.blend && blended(drawing, frame, element));
    const path = node("path", { d: pathOf(now || element.points, view.map), fill: "none", stroke: COLORS.element,
                                "stroke-width": "2.2", "stroke-linecap": "round", "data-element": element.name }, layer);
    node("title", {}, path).textContent = `element ${element.name} (${element.from} to ${element.to})`;
  }
}

function drawBodies(layer, drawing, frame, view) {
  for (const [name, body] of Object.entries(drawing.bodies)) {
    const moved = frame && frame.poses && frame.poses[name];
    for (const end of body.skeleton) {
      if (moved) node("path", { d: pathOf([body.reference, end], view.map), stroke: COLORS.undeformed, "stroke-dasharray": "4 3", fill: "none" }, layer);
      node("path", { d: pathOf([placed(drawing, frame, name, body.reference), placed(drawing, frame, name, end)], view.map),
                     stroke: COLORS.body, "stroke-width": "3", "stroke-linecap": "round", fill: "none" }, layer);
    }
    const [x, y] = view.map(placed(drawing, frame, name, body.reference));
    const marker = body.fixed
      ? node("rect", { x: x - 5, y: y - 5, width: 10, height: 10, fill: "#fff", stroke: COLORS.body, "stroke-width": "2" }, layer)
      : node("circle", { cx: x, cy: y, r: 3.5, fill: COLORS.body }, layer);
    marker.setAttribute("data-body", name);
    node("title", {}, marker).textContent = `body ${name}${body.fixed ? " (fixed)" : ""}`;
    node("text", { x: x + 7, y: y - 6, "font-size": "11", fill: COLORS.body }, layer).textContent = name;
  }
}

function springPath(a, b, map) {
  const [ax, ay] = map(a), [bx, by] = map(b);
  const length = Math.hypot(bx - ax, by - ay) || 1, ux = (bx - ax) / length, uy = (by - ay) / length;
  const parts = [`M${ax},${ay}`];
  for (let k = 1; k < 12; k++) {
    const t = k / 12, side = k % 2 ? 5 : -5;
    parts.push(`L${ax + ux * length * t - uy * side},${ay + uy * length * t + ux * side}`);
  }
  parts.push(`L${bx},${by}`);
  return parts.join("");
}

function drawConnectors(layer, drawing, frame, view) {
  for (const joint of drawing.connectors) {
    const [first, second] = joint.bodies;
    if (joint.glyph === "zigzag" && joint.points.length === 2) {
      const a = placed(drawing, frame, first, joint.points[0]), b = placed(drawing, frame, second, joint.points[1]);
      node("path", { d: springPath(a, b, view.map), fill: "none", stroke: COLORS.body, "stroke-width": "1.2", "data-connector": joint.name }, layer);
      continue;
    }
    const [x, y] = view.map(placed(drawing, frame, second, joint.points[0]));
    if (joint.glyph === "slider") {
      const c = Math.cos(joint.angle), s = Math.sin(joint.angle);
      node("line", { x1: x - 30 * c, y1: y + 30 * s, x2: x + 30 * c, y2: y - 30 * s, stroke: COLORS.body, "stroke-width": "1.2" }, layer);
      node("rect", { x: x - 8, y: y - 5, width: 16, height: 10, fill: "#fff", stroke: COLORS.body, "data-connector": joint.name,
                     transform: `rotate(${(-joint.angle * 180) / Math.PI} ${x} ${y})` }, layer);
    } else {
      node("circle", { cx: x, cy: y, r: 4.5, fill: "#fff", stroke: COLORS.body, "stroke-width": "1.6", "data-connector": joint.name }, layer);
    }
  }
}

function arrow(layer, tail, head, color, label, load = null) {
  const [tx, ty] = tail, [hx, hy] = head;
  const length = Math.hypot(hx - tx, hy - ty);
  if (length < 1) return;
  const ux = (hx - tx) / length, uy = (hy - ty) / length;
  const g = node("g", load === null ? { class: "arrow" } : { class: "arrow", "data-load": load }, layer);
  node("line", { x1: tx, y1: ty, x2: hx - 8 * ux, y2: hy - 8 * uy, stroke: color, "stroke-width": "2" }, g);
  node("path", { d: `M${hx},${hy}L${hx - 10 * ux - 4 * uy},${hy - 10 * uy + 4 * ux}L${hx - 10 * ux + 4 * uy},${hy - 10 * uy - 4 * ux}Z`, fill: color }, g);
  if (label) node("text", { x: tx - 4 * ux, y: ty - 4 * uy - 3, "font-size": "11", fill: color, "text-anchor": ux > 0 ? "end" : "start" }, g).textContent = label;
}

// A frame's loads are the drawing's, less those its `loads` give at its time (histories);
// `largestLoad` (the largest force of a whole animation) keeps the arrows' scale from frame to frame.
function drawLoads(layer, drawing, frame, view) {
  const loads = drawing.loads.map((l) => ({ ...l, ...((frame && frame.loads && frame.loads[l.name]) || {}) }));
  const forces = loads.filter((l) => l.kind === "force");
  const largest = (frame && frame.largestLoad) || Math.max(0, ...forces.map((l) => Math.hypot(...l.vector)));
  const pixels = ARROW_SPAN * (WIDTH - MARGIN.left - MARGIN.right);
  for (const load of loads) {
    const head = view.map(placed(drawing, frame, load.body, load.point));
    if (load.kind === "force") {
      const size = Math.hypot(...load.vector);
      if (!size) continue;
      const tail = [head[0] - (pixels * load.vector[0]) / largest, head[1] + (pixels * load.vector[1]) / largest];
      arrow(layer, tail, head, COLORS.load, `${load.name} ${formatNumber(size)} ${drawing.units.force}`, load.name);
    } else {
      const r = 16, sweep = load.value >= 0 ? 0 : 1;
      node("path", { d: `M${head[0] + r},${head[1]}A${r},${r} 0 1 ${sweep} ${head[0]},${head[1] + (sweep ? r : -r)}`, fill: "none", stroke: COLORS.load, "stroke-width": "2" }, layer);
      node("text", { x: head[0] + r + 3, y: head[1] - r, "font-size": "11", fill: COLORS.load, "data-load": load.name }, layer).textContent = `${load.name} ${formatNumber(load.value)} ${drawing.units.moment}`;
    }
  }
}

function drawPoints(layer, drawing, frame, view) {
  for (const point of drawing.points) {
    const [x, y] = view.map(placed(drawing, frame, point.body, point.point));
    node("path", { d: `M${x},${y - 6}L${x + 5},${y + 4}L${x - 5},${y + 4}Z`, fill: COLORS.point, "data-point": point.name }, layer);
    node("text", { x: x + 7, y: y + 12, "font-size": "11", fill: COLORS.point }, layer).textContent = point.name;
  }
}

function drawOverlay(layer, overlay, view) {
  if (!overlay) return;
  for (const line of overlay.lines || []) {
    node("path", { d: pathOf(line.points, view.map, line.closed), fill: line.fill || "none", "fill-opacity": "0.6",
                   stroke: line.color || COLORS.element, "stroke-width": line.width || "1.6", "stroke-dasharray": line.dashed ? "3 3" : "" }, layer);
  }
  const largest = Math.max(0, ...(overlay.forces || []).map((f) => Math.hypot(...f.vector)));
  for (const force of overlay.forces || []) {
    const head = view.map(force.point);
    const scale = (ARROW_SPAN * (WIDTH - MARGIN.left - MARGIN.right)) / (overlay.largestForce || largest || 1);
    arrow(layer, [head[0] - force.vector[0] * scale, head[1] + force.vector[1] * scale], head, COLORS.force, force.label);
  }
}

// Draw `drawing` (a /v1/drawings answer) into `container`, in the frame given (null: undeformed).
export function drawScene(container, drawing, frame = null, bounds = null) {
  const svg = node("svg", { viewBox: `0 0 ${WIDTH} ${HEIGHT}`, xmlns: SVG, role: "img", "font-family": "system-ui, sans-serif",
                            "aria-label": `${drawing.name}, drawn to scale in ${drawing.units.length}` });
  node("title", {}, svg).textContent = drawing.name;
  node("rect", { x: 0, y: 0, width: WIDTH, height: HEIGHT, fill: "#fff" }, svg);
  const whole = bounds || sceneBounds(drawing, [null, frame]);
  const viewed = viewedBounds(container, drawing, whole, () => drawScene(container, drawing, frame, bounds));
  const view = transform(viewed);
  drawAxes(svg, view, drawing.units.length);
  const layer = node("g", {}, svg);
  if (viewed.some((v, i) => v !== whole[i])) { // zoomed or panned: nothing drawn over the axes
    const clip = node("clipPath", { id: "plot-area" }, node("defs", {}, svg));
    node("rect", { x: MARGIN.left, y: MARGIN.top, width: WIDTH - MARGIN.left - MARGIN.right, height: HEIGHT - MARGIN.top - MARGIN.bottom }, clip);
    layer.setAttribute("clip-path", "url(#plot-area)");
  }
  const scale = stressScale(drawing, frame);
  drawOutlines(layer, drawing, frame, view);
  drawElements(layer, drawing, frame, view, scale);
  drawConnectors(layer, drawing, frame, view);
  drawBodies(layer, drawing, frame, view);
  drawPoints(layer, drawing, frame, view);
  drawLoads(layer, drawing, frame, view);
  drawOverlay(layer, frame && frame.overlay, view);
  const grow = Math.min(2, Math.max(1, 560 / (container.clientWidth || WIDTH))); // legible on a phone
  if (scale) drawColourBar(svg, scale, { right: WIDTH - MARGIN.right, top: MARGIN.top, grow });
  if (frame && frame.label) node("text", { x: WIDTH - MARGIN.right - 6, y: MARGIN.top + 16, "text-anchor": "end", "font-size": "13", fill: COLORS.body, class: "frame-label" }, svg).textContent = frame.label;
  container.replaceChildren(svg);
  drawn(container, view, svg);
  return svg;
}
