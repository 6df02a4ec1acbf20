// A tolerance report in the page: its responses and the sources' contributions as tables, the
// yield in the diagnostics, and two charts per response: the Monte Carlo histogram (the samples'
// density as steps) with the first-order normal density and the spec's bounds, and a tornado of
// the sources' contributions (the response's move per standard deviation of each, largest on top).

import { PALETTE, linePlot } from "./plot.js";

const SVG_NS = "http://www.w3.org/2000/svg";
const MAX_CHARTS = 8; // responses drawn (the tables list every one)
const BAR = 26; // px per source in a tornado

export function toleranceView(v, report) {
  const rows = [], contributions = [];
  for (const [name, entry] of Object.entries(report.responses || {})) {
    const sampled = entry.monte_carlo || {}, spec = entry.spec || {};
    rows.push([name, entry.nominal, entry.first_order.std, sampled.mean ?? null, sampled.std ?? null, spec.min ?? null,
               spec.max ?? null, entry.unit, entry.linearity.near_linear ? "near" : "no"]);
    for (const c of entry.first_order.contributions) contributions.push([name, c.source, c.per_sigma, 100 * c.share, entry.unit]);
  }
  v.tables.push({ caption: "Responses: first order (its mean is the nominal value) and Monte Carlo (MC)",
                  columns: ["response", "nominal", "std", "mean (MC)", "std (MC)", "spec min", "spec max", "unit", "linear"], rows });
  v.tables.push({ caption: "Contributions (first order), largest first", columns: ["response", "source", "per sigma", "share [%]", "unit"],
                  rows: contributions });
  const found = report.yield;
  if (found) {
    v.summary.unshift(["yield (Monte Carlo)", `${(100 * found.monte_carlo).toFixed(2)} % ± ${(100 * found.standard_error).toFixed(2)} % of ${found.samples} samples`],
                      ["yield (first order, the same samples)", `${(100 * found.first_order).toFixed(2)} %`]);
  }
  v.charts = Object.entries(report.responses || {}).slice(0, MAX_CHARTS)
    .flatMap(([name, entry]) => [() => histogram(name, entry), () => tornado(name, entry)]);
  return v;
}

function histogram(name, entry) {
  const label = entry.unit ? `${name} [${entry.unit}]` : name;
  const series = [];
  const counts = ((entry.monte_carlo || {}).histogram || {}).counts;
  if (counts) {
    const { edges } = entry.monte_carlo.histogram;
    const total = counts.reduce((a, b) => a + b, 0) || 1;
    const x = [], y = [];
    counts.forEach((count, i) => { const density = count / total / (edges[i + 1] - edges[i]); x.push(edges[i], edges[i + 1]); y.push(density, density); });
    series.push({ name: "Monte Carlo", x, y, color: PALETTE[0] });
  }
  const { mean, std } = entry.first_order;
  if (std > 0) {
    const x = Array.from({ length: 161 }, (_, i) => mean + (i / 20 - 4) * std);
    series.push({ name: "first order", x, y: x.map((u) => Math.exp(-0.5 * ((u - mean) / std) ** 2) / (std * Math.sqrt(2 * Math.PI))), color: PALETTE[1], dash: "8 4" });
  }
  const top = Math.max(...series.flatMap((s) => s.y));
  for (const [bound, value] of Object.entries(entry.spec || {})) {
    if (value !== null && value !== undefined) series.push({ name: `spec ${bound}`, x: [value, value], y: [0, top], color: PALETTE[6], dash: "2 3" });
  }
  return linePlot({ series, xLabel: label, yLabel: "density", title: `${name}: the samples and first order` });
}

function tornado(name, entry) {
  const contributions = entry.first_order.contributions.slice(0, 12);
  const width = 640, left = 220, right = 90, height = 48 + BAR * contributions.length;
  const svg = document.createElementNS(SVG_NS, "svg");
  for (const [k, value] of Object.entries({ width, height, viewBox: `0 0 ${width} ${height}`, role: "img", class: "tornado",
                                            "font-size": 12, "font-family": "system-ui, sans-serif" })) svg.setAttribute(k, String(value));
  const add = (tag, attributes, text) => {
    const element = document.createElementNS(SVG_NS, tag);
    for (const [k, value] of Object.entries(attributes)) element.setAttribute(k, String(value));
    if (text !== undefined) element.textContent = text;
    svg.append(element);
    return element;
  };
  add("title", {}, `${name}: contributions`);
  add("text", { x: 8, y: 18, "font-weight": "bold" }, `${name}: per standard deviation of each source [${entry.unit}]`);
  const largest = Math.max(...contributions.map((c) => Math.abs(c.per_sigma)), 1e-300);
  const middle = left + (width - left - right) / 2, half = (width - left - right) / 2;
  add("line", { x1: middle, x2: middle, y1: 28, y2: height - 8, stroke: "#222" });
  contributions.forEach((c, k) => {
    const y = 32 + k * BAR, length = (c.per_sigma / largest) * half;
    add("rect", { x: Math.min(middle, middle + length), y, width: Math.abs(length), height: BAR - 8, fill: c.per_sigma >= 0 ? PALETTE[0] : PALETTE[1], class: "tornado-bar" });
    add("text", { x: left - 8, y: y + BAR / 2, "text-anchor": "end" }, c.source);
    add("text", { x: width - right + 6, y: y + BAR / 2 }, `${(100 * c.share).toFixed(1)} %`);
  });
  return svg;
}
