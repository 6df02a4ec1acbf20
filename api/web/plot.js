// Line plots as self-contained SVG: nice axes, a legend, hover and keyboard read-out of the
// nearest data point, and export of the figure as an SVG document or a PNG. Every style is an
// attribute (no stylesheet), so a downloaded figure looks the same outside the page.

const SVG_NS = "http://www.w3.org/2000/svg";
const FONT = "system-ui, -apple-system, 'Segoe UI', Roboto, Arial, sans-serif";
// Okabe–Ito: distinguishable with the common colour-vision deficiencies; yellow last (faint on white).
export const PALETTE = ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000", "#F0E442"];
// Dash patterns told apart at a glance (solid first), for series that share a colour family or a legend.
export const DASHES = ["", "8 4", "2 3", "10 3 2 3"];
const INK = "#222", MUTED = "#555", GRID = "#e6e6e6", FRAME = "#9a9a9a";
const CHAR_WIDTH = 6.8; // rough width of a 12px sans-serif character, for layout before rendering
const LINE_HEIGHT = 16;
const MAX_MARKERS = 1000; // `points` markers per series beyond which they would only clutter the DOM

function node(name, attributes = {}, parent = null) {
  const element = document.createElementNS(SVG_NS, name);
  for (const [key, value] of Object.entries(attributes)) element.setAttribute(key, String(value));
  if (parent) parent.append(element);
  return element;
}

const isFiniteNumber = (value) => typeof value === "number" && Number.isFinite(value);
const fixed = (value) => Math.round(value * 10) / 10; // 0.1 px is finer than any screen needs

export function formatNumber(value) {
  if (typeof value !== "number" || Number.isNaN(value)) return "–";
  if (!Number.isFinite(value)) return value > 0 ? "∞" : "−∞";
  if (value === 0) return "0";
  // Decide the notation on the rounded value, so 99999.9 becomes 1e+5 rather than "100000".
  const rounded = Number(value.toPrecision(4));
  const size = Math.abs(rounded);
  if (size >= 1e5 || size < 1e-3) return rounded.toExponential(3).replace(/\.?0+e/, "e");
  return String(rounded);
}

export function niceTicks(min, max, count = 6) {
  if (!Number.isFinite(min) || !Number.isFinite(max)) return [];
  [min, max] = padRange(Math.min(min, max), Math.max(min, max));
  const wanted = Math.max(2, Math.round(count) || 2);
  const raw = (max - min) / (wanted - 1);
  const decade = 10 ** Math.floor(Math.log10(raw));
  // Of the 1-2-5 steps near the raw step, the one giving the tick count closest to the wish.
  let best = null;
  for (const mantissa of [1, 2, 5, 10]) {
    const step = mantissa * decade;
    const first = Math.floor(min / step + 1e-9), last = Math.ceil(max / step - 1e-9);
    const miss = Math.abs(last - first + 1 - wanted);
    if (!best || miss < best.miss) best = { step, first, last, miss };
  }
  const ticks = [];
  // Multiples of the step, rounded to shed binary noise (0.30000000000000004 -> 0.3).
  for (let k = best.first; k <= best.last; k++) ticks.push(Number((k * best.step).toPrecision(12)) || 0);
  return ticks;
}

// A range that is never empty: equal ends are spread around their value.
function padRange(min, max) {
  if (max > min) return [min, max];
  const pad = min === 0 ? 1 : Math.abs(min) * 0.1;
  return [min - pad, max + pad];
}

// A log axis draws log10 of its values (a value not above 0 is a gap). Its ticks, in log10
// units: the decades, with 2 and 5 times each when the axis spans few (`minor`: the rest of
// 2..9 times each decade, grid lines without labels); under a decade, the 1-2-5 ticks of the
// values themselves. From the last tick at or below `min` to the first at or above `max`.
export function logTicks(min, max, count = 6) {
  if (!Number.isFinite(min) || !Number.isFinite(max)) return { major: [], minor: [] };
  [min, max] = padRange(Math.min(min, max), Math.max(min, max));
  const first = Math.floor(min + 1e-9), last = Math.ceil(max - 1e-9);
  if (last - first < 2) { // within about a decade: plain nice values (when they cover it), drawn at their logs
    const values = niceTicks(10 ** min, 10 ** max, count).filter((v) => v > 0).map(Math.log10);
    if (values.length >= 2 && values[0] <= min + 1e-9 && values[values.length - 1] >= max - 1e-9) return { major: values, minor: [] };
  }
  const every = Math.max(1, Math.ceil((last - first + 1) / Math.max(2, count))); // decades per labelled tick
  const sub = (last - first) * 3 <= count ? [1, 2, 5] : [1];
  const major = [], minor = [];
  for (let k = first; k <= last; k += 1) {
    for (let m = 1; m < 10; m += 1) {
      const at = k + Math.log10(m);
      if ((k - first) % every === 0 && sub.includes(m)) major.push(at); else if (every === 1) minor.push(at);
    }
  }
  const low = Math.max(...major.filter((t) => t <= min + 1e-9)), high = Math.min(...major.filter((t) => t >= max - 1e-9));
  const within = (t) => t >= low - 1e-9 && t <= high + 1e-9;
  return { major: major.filter(within), minor: minor.filter(within) };
}

const logOf = (values) => values.map((v) => (isFiniteNumber(v) && v > 0 ? Math.log10(v) : null));
// A tick's label: the value itself on a log axis (its log10 is where it is drawn).
const tickText = (log) => (value) => formatNumber(log ? Number((10 ** value).toPrecision(12)) : value);

function dataExtent(series) {
  let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
  for (const { x, y } of series) {
    for (let i = 0; i < x.length; i++) {
      const xi = x[i], yi = y[i];
      if (!isFiniteNumber(xi) || !isFiniteNumber(yi)) continue;
      if (xi < x0) x0 = xi;
      if (xi > x1) x1 = xi;
      if (yi < y0) y0 = yi;
      if (yi > y1) y1 = yi;
    }
  }
  return x0 <= x1 ? { x: padRange(x0, x1), y: padRange(y0, y1) } : null;
}

// Same-length arrays, a colour and a search strategy per series, whatever the caller passed.
// On a log axis a series is drawn by the log10 of its values; `shownX`, `shownY` keep the
// values themselves for the read-out.
function normalizeSeries(series, log = { x: false, y: false }) {
  return (Array.isArray(series) ? series : []).map((s, index) => {
    const x = s && s.x ? s.x : [], y = s && s.y ? s.y : [];
    const length = Math.min(x.length, y.length);
    const name = s && s.name !== undefined ? String(s.name) : `series ${index + 1}`;
    const color = (s && s.color) || PALETTE[index % PALETTE.length];
    const dash = (s && s.dash) || (s && s.dashed ? "6 4" : "");
    const shownX = x.slice(0, length), shownY = y.slice(0, length);
    const drawnX = log.x ? logOf(shownX) : shownX, drawnY = log.y ? logOf(shownY) : shownY;
    return { name, color, dash, x: drawnX, y: drawnY, shownX, shownY, order: xOrder(drawnX, length) };
  });
}

// +1 / -1 when x only grows / only shrinks (and is all finite): then hover can binary search.
function xOrder(x, length) {
  let up = true, down = true;
  for (let i = 0; i < length; i++) {
    if (!isFiniteNumber(x[i])) return 0;
    if (i && x[i] < x[i - 1]) up = false;
    if (i && x[i] > x[i - 1]) down = false;
  }
  return up ? 1 : down ? -1 : 0;
}

// Legend entries placed in rows above the plot, wrapping when the width is used up.
function legendLayout(series, width) {
  if (series.length < 2) return { items: [], rows: 0 };
  const items = [];
  let x = 16, row = 0;
  for (const s of series) {
    const itemWidth = 30 + s.name.length * CHAR_WIDTH;
    if (x > 16 && x + itemWidth > width - 16) { x = 16; row++; }
    items.push({ series: s, x, row });
    x += itemWidth + 14;
  }
  return { items, rows: row + 1 };
}

function layoutOf({ width, height, title, legendRows, yTickLabels }) {
  const top = (title ? 30 : 12) + legendRows * LINE_HEIGHT + (legendRows ? 6 : 0);
  const widest = Math.max(1, ...yTickLabels.map((label) => label.length));
  const left = Math.round(34 + widest * CHAR_WIDTH);
  const right = width - 18, bottom = height - 42;
  return { left, right, top, bottom, width: Math.max(1, right - left), height: Math.max(1, bottom - top) };
}

function scalesOf(area, xDomain, yDomain) {
  const [x0, x1] = xDomain, [y0, y1] = yDomain;
  return {
    x: (v) => area.left + ((v - x0) / (x1 - x0)) * area.width,
    y: (v) => area.bottom - ((v - y0) / (y1 - y0)) * area.height,
    xOf: (px) => x0 + ((px - area.left) / area.width) * (x1 - x0),
  };
}

// Drawn after the grid, which would otherwise paint over the frame's edges.
const drawFrame = (svg, area) => node("rect", { x: area.left, y: area.top, width: area.width, height: area.height, fill: "none", stroke: FRAME }, svg);

function drawLabels(svg, area, { xLabel, yLabel, title, width, height }) {
  node("text", { x: area.left + area.width / 2, y: height - 8, "text-anchor": "middle", fill: INK, class: "plot-x-label" }, svg).textContent = xLabel;
  const middle = area.top + area.height / 2;
  node("text", { x: 14, y: middle, transform: `rotate(-90 14 ${middle})`, "text-anchor": "middle", "dominant-baseline": "middle", fill: INK, class: "plot-y-label" }, svg).textContent = yLabel;
  if (title) node("text", { x: width / 2, y: 20, "text-anchor": "middle", "font-size": 14, "font-weight": 600, fill: INK, class: "plot-title" }, svg).textContent = title;
}

// Ticks are where they are drawn (log10 of the value on a log axis: `text` labels them);
// `minor` ticks are grid lines alone (a log axis' 2..9 times a decade).
function drawTicks(svg, area, scales, x, y) {
  const minorGrid = node("g", { stroke: GRID, "stroke-width": 0.5, "stroke-dasharray": "2 3" }, svg);
  const grid = node("g", { stroke: GRID, "stroke-width": 1 }, svg);
  const labels = node("g", { fill: MUTED }, svg);
  for (const value of x.minor) { const px = fixed(scales.x(value)); node("line", { x1: px, x2: px, y1: area.top, y2: area.bottom }, minorGrid); }
  for (const value of y.minor) { const py = fixed(scales.y(value)); node("line", { x1: area.left, x2: area.right, y1: py, y2: py }, minorGrid); }
  for (const value of x.major) {
    const px = fixed(scales.x(value));
    node("line", { x1: px, x2: px, y1: area.top, y2: area.bottom }, grid);
    node("text", { x: px, y: area.bottom + 15, "text-anchor": "middle", class: "plot-x-tick" }, labels).textContent = x.text(value);
  }
  for (const value of y.major) {
    const py = fixed(scales.y(value));
    node("line", { x1: area.left, x2: area.right, y1: py, y2: py }, grid);
    node("text", { x: area.left - 6, y: py + 4, "text-anchor": "end", class: "plot-y-tick" }, labels).textContent = y.text(value);
  }
}

// Path data with a new subpath after every gap (null or non-finite x or y). Long series are
// decimated: consecutive points in one pixel column keep only first, lowest, highest and last,
// so the shape and its spikes survive while the path stays a few thousand points long.
function pathData(s, scales, decimate) {
  const parts = [];
  let run = null, segmentLength = 0;
  const emit = (px, py) => { parts.push(`${segmentLength ? "L" : "M"}${fixed(px)},${fixed(py)}`); segmentLength++; };
  const flush = () => {
    if (!run) return;
    const kept = [run.first, run.low, run.high, run.last].sort((a, b) => a.i - b.i);
    kept.forEach((p, k) => { if (!k || p.i !== kept[k - 1].i) emit(p.px, p.py); });
    run = null;
  };
  const endSegment = () => { flush(); if (segmentLength === 1) parts.push("h0"); segmentLength = 0; };
  for (let i = 0; i < s.x.length; i++) {
    if (!isFiniteNumber(s.x[i]) || !isFiniteNumber(s.y[i])) { endSegment(); continue; }
    const p = { i, px: scales.x(s.x[i]), py: scales.y(s.y[i]) };
    if (!decimate) { emit(p.px, p.py); continue; }
    const column = Math.round(p.px);
    if (run && run.column !== column) flush();
    if (!run) run = { column, first: p, low: p, high: p, last: p };
    run.last = p;
    if (p.py > run.low.py) run.low = p;
    if (p.py < run.high.py) run.high = p;
  }
  endSegment();
  return parts.join("");
}

function drawSeries(svg, series, scales, area, points) {
  const layer = node("g", { fill: "none", "stroke-width": 1.75, "stroke-linejoin": "round", "stroke-linecap": "round" }, svg);
  for (const s of series) {
    const decimate = s.x.length > 4 * area.width;
    const attributes = { d: pathData(s, scales, decimate), stroke: s.color, class: "plot-series" };
    if (s.dash) attributes["stroke-dasharray"] = s.dash;
    node("path", attributes, layer);
    if (!points || s.x.length > MAX_MARKERS) continue;
    const markers = node("g", { fill: s.color, stroke: "none" }, layer);
    for (let i = 0; i < s.x.length; i++) {
      if (isFiniteNumber(s.x[i]) && isFiniteNumber(s.y[i])) node("circle", { cx: fixed(scales.x(s.x[i])), cy: fixed(scales.y(s.y[i])), r: 2.5 }, markers);
    }
  }
}

function drawLegend(svg, legend, titleHeight) {
  const group = node("g", { class: "plot-legend", fill: INK }, svg);
  for (const { series: s, x, row } of legend.items) {
    const y = titleHeight + row * LINE_HEIGHT + 8;
    const sample = { x1: x, x2: x + 24, y1: y, y2: y, stroke: s.color, "stroke-width": 2 };
    if (s.dash) sample["stroke-dasharray"] = s.dash;
    node("line", sample, group);
    node("text", { x: x + 30, y: y + 4 }, group).textContent = s.name;
  }
}

// The nearest point (pixel distance) of one series to (px, py): for x monotonic, a binary search
// and a walk outwards that stops once x alone is farther than the best found; else a full scan.
function nearestInSeries(s, scales, px, py, best) {
  const consider = (i) => {
    if (!isFiniteNumber(s.x[i]) || !isFiniteNumber(s.y[i])) return;
    const distance = Math.hypot(scales.x(s.x[i]) - px, scales.y(s.y[i]) - py);
    if (distance < best.distance) Object.assign(best, { series: s, index: i, distance });
  };
  if (!s.order) { for (let i = 0; i < s.x.length; i++) consider(i); return best; }
  const target = s.order * scales.xOf(px);
  let low = 0, high = s.x.length;
  while (low < high) { const mid = (low + high) >> 1; if (s.order * s.x[mid] < target) low = mid + 1; else high = mid; }
  for (let i = low; i < s.x.length && Math.abs(scales.x(s.x[i]) - px) < best.distance; i++) consider(i);
  for (let i = low - 1; i >= 0 && Math.abs(scales.x(s.x[i]) - px) < best.distance; i--) consider(i);
  return best;
}

function tooltipSize(text, lines) {
  let widest = 0;
  try { for (const line of text.children) widest = Math.max(widest, line.getComputedTextLength()); } catch { widest = 0; }
  // Not rendered yet (detached or hidden): estimate from the character count.
  if (!widest) widest = Math.max(...lines.map((line) => line.length)) * CHAR_WIDTH;
  return { width: widest + 16, height: lines.length * LINE_HEIGHT + 8 };
}

function createHover(svg, area) {
  const group = node("g", { class: "plot-hover", "pointer-events": "none", display: "none", "data-plot-transient": "true" }, svg);
  const crosshair = { stroke: "#888", "stroke-width": 1, "stroke-dasharray": "3 3" };
  const vertical = node("line", { ...crosshair, y1: area.top, y2: area.bottom }, group);
  const horizontal = node("line", { ...crosshair, x1: area.left, x2: area.right }, group);
  const marker = node("circle", { r: 4.5, stroke: "#fff", "stroke-width": 2 }, group);
  const box = node("rect", { rx: 3, fill: "#fff", "fill-opacity": 0.94, stroke: "#999" }, group);
  const text = node("text", { class: "plot-tooltip", fill: INK }, group);
  return { group, vertical, horizontal, marker, box, text };
}

function showPoint(hover, area, scales, s, index) {
  const px = scales.x(s.x[index]), py = scales.y(s.y[index]);
  hover.vertical.setAttribute("x1", fixed(px)); hover.vertical.setAttribute("x2", fixed(px));
  hover.horizontal.setAttribute("y1", fixed(py)); hover.horizontal.setAttribute("y2", fixed(py));
  hover.marker.setAttribute("cx", fixed(px)); hover.marker.setAttribute("cy", fixed(py));
  hover.marker.setAttribute("fill", s.color);
  const lines = [s.name, `x = ${formatNumber(s.shownX[index])}`, `y = ${formatNumber(s.shownY[index])}`];
  hover.text.replaceChildren(...lines.map((line, k) => {
    const span = node("tspan", { dy: k ? LINE_HEIGHT : 0, "font-weight": k ? 400 : 600 });
    span.textContent = line;
    return span;
  }));
  hover.group.removeAttribute("display");
  const size = tooltipSize(hover.text, lines);
  // Up and right of the point, flipped to stay inside the plot area.
  let left = px + 12 + size.width > area.right ? px - 12 - size.width : px + 12;
  let top = py - 12 - size.height < area.top ? py + 12 : py - 12 - size.height;
  left = Math.max(area.left + 2, Math.min(left, area.right - size.width - 2));
  top = Math.max(area.top + 2, Math.min(top, area.bottom - size.height - 2));
  Object.entries({ x: left, y: top, width: size.width, height: size.height }).forEach(([k, v]) => hover.box.setAttribute(k, fixed(v)));
  hover.text.setAttribute("y", fixed(top + 4 + 12));
  for (const span of hover.text.children) span.setAttribute("x", fixed(left + 8));
}

// The index reached from `from` by `step` (±), skipping gaps; clamps at the ends.
function validIndex(s, from, step) {
  const valid = (i) => isFiniteNumber(s.x[i]) && isFiniteNumber(s.y[i]);
  const last = s.x.length - 1;
  let i = Math.max(0, Math.min(last, from));
  const direction = step < 0 ? -1 : 1;
  while (i >= 0 && i <= last && !valid(i)) i += direction;
  if (i >= 0 && i <= last) return i;
  for (i = Math.max(0, Math.min(last, from)); i >= 0 && i <= last; i -= direction) if (valid(i)) return i;
  return -1;
}

function wireInteraction(svg, series, area, scales) {
  const hover = createHover(svg, area);
  const state = { series: series.find((s) => validIndex(s, 0, 1) >= 0) || series[0], index: -1 };
  const show = (s, index) => { if (index < 0) return; Object.assign(state, { series: s, index }); showPoint(hover, area, scales, s, index); };
  const hide = () => { state.index = -1; hover.group.setAttribute("display", "none"); };
  // Invisible, on top of the lines, so the pointer is tracked over the whole plot area only.
  const catcher = node("rect", { x: area.left, y: area.top, width: area.width, height: area.height, fill: "#fff", "fill-opacity": 0, "pointer-events": "all", "data-plot-transient": "true" });
  svg.insertBefore(catcher, hover.group);
  catcher.addEventListener("pointermove", (event) => {
    const matrix = svg.getScreenCTM();
    if (!matrix) return;
    const p = new DOMPoint(event.clientX, event.clientY).matrixTransform(matrix.inverse());
    const best = { series: null, index: -1, distance: Infinity };
    for (const s of series) nearestInSeries(s, scales, p.x, p.y, best);
    if (best.series) show(best.series, best.index); else hide();
  });
  catcher.addEventListener("pointerleave", hide);
  svg.addEventListener("keydown", (event) => {
    const s = state.series, n = s.x.length, page = Math.max(1, Math.round(n / 20));
    const at = state.index;
    const moves = { ArrowRight: [at < 0 ? 0 : at + 1, 1], ArrowLeft: [at < 0 ? n - 1 : at - 1, -1], PageDown: [at + page, 1],
                    PageUp: [at < 0 ? n - 1 : at - page, -1], Home: [0, 1], End: [n - 1, -1] };
    if (event.key === "Escape") hide();
    else if (moves[event.key] && n) show(s, validIndex(s, ...moves[event.key]));
    else return;
    event.preventDefault(); // the keys move the read-out, not the page
  });
}

function emptyRoot({ width, height, label }) {
  const svg = node("svg", { xmlns: SVG_NS, viewBox: `0 0 ${width} ${height}`, width: "100%", preserveAspectRatio: "xMidYMid meet",
                            role: "img", tabindex: 0, "aria-label": label, "font-family": FONT, "font-size": 12, class: "line-plot" });
  node("title", {}, svg).textContent = label;
  node("rect", { x: 0, y: 0, width, height, fill: "#fff" }, svg);
  return svg;
}

// series: [{name, x: number[], y: (number|null)[], color?, dash? (an SVG dash array), dashed?}];
// xLog, yLog: that axis is logarithmic (values not above 0 are gaps). Returns an <svg> element.
export function linePlot({ series = [], xLabel = "", yLabel = "", title = "", width = 640, height = 360, points = false,
                           xLog = false, yLog = false } = {}) {
  const label = title || `${yLabel} against ${xLabel}`;
  const svg = emptyRoot({ width, height, label });
  if (xLog) svg.dataset.xScale = "log";
  if (yLog) svg.dataset.yScale = "log";
  const list = normalizeSeries(series, { x: xLog, y: yLog });
  const extent = dataExtent(list);
  const legend = legendLayout(list, width);
  const titleHeight = title ? 30 : 12;
  const yCount = Math.max(3, Math.round((height - 80) / 50));
  const yAxis = { minor: [], text: tickText(yLog), ...(!extent ? { major: [] } : yLog ? logTicks(extent.y[0], extent.y[1], yCount) : { major: niceTicks(extent.y[0], extent.y[1], yCount) }) };
  const yTicks = yAxis.major;
  const area = layoutOf({ width, height, title, legendRows: legend.rows, yTickLabels: yTicks.map(yAxis.text) });
  drawLabels(svg, area, { xLabel, yLabel, title, width, height });
  if (!extent) {
    drawFrame(svg, area);
    node("text", { x: area.left + area.width / 2, y: area.top + area.height / 2, "text-anchor": "middle", fill: MUTED, class: "plot-no-data" }, svg).textContent = "no data";
    return svg;
  }
  // y spans whole ticks (lines keep off the frame); x is tight, lines reach both sides.
  const scales = scalesOf(area, extent.x, [yTicks[0], yTicks[yTicks.length - 1]]);
  const span = extent.x[1] - extent.x[0];
  const xCount = Math.max(2, Math.round(area.width / 90));
  const inside = (v) => v >= extent.x[0] - span * 1e-9 && v <= extent.x[1] + span * 1e-9;
  const xAxis = { minor: [], text: tickText(xLog), ...(xLog ? logTicks(extent.x[0], extent.x[1], xCount) : { major: niceTicks(extent.x[0], extent.x[1], xCount) }) };
  drawTicks(svg, area, scales, { ...xAxis, major: xAxis.major.filter(inside), minor: xAxis.minor.filter(inside) }, yAxis);
  drawFrame(svg, area);
  drawSeries(svg, list, scales, area, points);
  drawLegend(svg, legend, titleHeight);
  wireInteraction(svg, list, area, scales);
  return svg;
}

// [x, y, width, height] of the figure: its viewBox, else its size attributes, else its box.
function figureBox(svg) {
  const box = svg.viewBox && svg.viewBox.baseVal;
  if (box && box.width > 0 && box.height > 0) return [box.x, box.y, box.width, box.height];
  const width = parseFloat(svg.getAttribute("width")), height = parseFloat(svg.getAttribute("height"));
  if (width > 0 && height > 0 && !/%/.test(svg.getAttribute("width") + svg.getAttribute("height"))) return [0, 0, width, height];
  const rect = svg.getBoundingClientRect();
  return [0, 0, rect.width || 640, rect.height || 360];
}

export function svgMarkup(svg) {
  const copy = svg.cloneNode(true);
  // The hover read-out and pointer catcher belong to the page, not to the figure.
  copy.querySelectorAll("[data-plot-transient]").forEach((element) => element.remove());
  const [x, y, width, height] = figureBox(svg);
  copy.setAttribute("xmlns", SVG_NS);
  copy.setAttribute("viewBox", `${x} ${y} ${width} ${height}`);
  // A fixed size, because a percentage means nothing in a file (or to an <img>).
  copy.setAttribute("width", String(width));
  copy.setAttribute("height", String(height));
  copy.removeAttribute("tabindex");
  if (!copy.getAttribute("font-family")) copy.setAttribute("font-family", FONT);
  return `<?xml version="1.0" encoding="UTF-8"?>\n${new XMLSerializer().serializeToString(copy)}`;
}

export async function svgToPngBlob(svg, scale = 2) {
  const [, , width, height] = figureBox(svg);
  const image = new Image();
  // A data URL (not a blob URL) keeps the canvas untainted in every browser.
  image.src = `data:image/svg+xml;charset=utf-8,${encodeURIComponent(svgMarkup(svg))}`;
  await image.decode();
  const canvas = document.createElement("canvas");
  canvas.width = Math.max(1, Math.round(width * scale));
  canvas.height = Math.max(1, Math.round(height * scale));
  const context = canvas.getContext("2d");
  context.fillStyle = "#fff";
  context.fillRect(0, 0, canvas.width, canvas.height);
  context.drawImage(image, 0, 0, canvas.width, canvas.height);
  return new Promise((resolve, reject) => {
    canvas.toBlob((blob) => (blob ? resolve(blob) : reject(new Error("the figure could not be encoded as PNG"))), "image/png");
  });
}
