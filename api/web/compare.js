// Runs side by side in the Curves tab. "Keep for comparison" keeps the run shown (its series
// and their units, labelled by what ran it: the analysis or job, the curved-beam model, the
// time, e.g. "sweep job, exact model, 14:02:31"); the plot then draws each kept run's curve of
// the two quantities on the axes over the current one, each in its own colour and dash, with
// a legend, while the run has both quantities in the axes' units. The list under the plot
// names every kept run, says why one is not drawn, and removes one or all.

import { seriesName } from "./names.js";
import { DASHES, PALETTE } from "./plot.js";

const $ = (id) => document.getElementById(id);
const SVG_NS = "http://www.w3.org/2000/svg";
const COLOURS = PALETTE.slice(1, -1); // the current curve has the first; yellow is too faint on white

const kept = []; // {id, view, label, document, color, dash}
let made = 0; // runs kept so far: each gets the next colour and dash, kept when others go

// "sweep (job)" as the Run menu says it, "sweep job" as a label.
const titleOf = (title) => (title || "run").replace(/ \(job\)$/, " job");

function modelOf(value) {
  const option = [...$("model").options].find((o) => o.value === (value || ""));
  if (!value) return "model as in the document";
  return `${option ? option.text : value.replace(/_/g, " ")} model`;
}

const clock = (at) => new Date(at).toLocaleTimeString([], { hour: "2-digit", minute: "2-digit", second: "2-digit", hour12: false });

// What a run is called in the legend and the list; `run` is what main.js records with a view.
export function runLabel(run) {
  if (!run) return "run";
  return `${titleOf(run.title)}, ${modelOf(run.model)}, ${clock(run.at)}`;
}

export function isKept(view) {
  return Boolean(view) && kept.some((k) => k.view === view);
}

// The view kept (once); false when there is nothing to keep.
export function keep(view) {
  if (!view || Object.keys(view.series).length < 2 || isKept(view)) return false;
  kept.push({ id: made, view, label: runLabel(view.run), document: (view.run && view.run.document) || "",
              color: COLOURS[made % COLOURS.length], dash: DASHES[made % DASHES.length] });
  made += 1;
  return true;
}

// Why a kept run's curve of y against x is not on axes in `units` ({x, y}); "" when it is.
function whyNot(run, x, y, units) {
  if (!x || !y) return "no curve is shown";
  for (const [name, unit] of [[x, units.x], [y, units.y]]) {
    if (!run.view.series[name]) return `it has no ${seriesName(run.view, name)}`;
    const own = run.view.units[name] || "";
    if (own !== unit) return `its ${seriesName(run.view, name)} is in ${own || "no unit"}, the axis in ${unit || "no unit"}`;
  }
  return "";
}

function swatch(color, dash) {
  const svg = document.createElementNS(SVG_NS, "svg");
  svg.setAttribute("width", "28"); svg.setAttribute("height", "10"); svg.setAttribute("aria-hidden", "true");
  const line = document.createElementNS(SVG_NS, "line");
  for (const [key, value] of Object.entries({ x1: 1, x2: 27, y1: 5, y2: 5, stroke: color, "stroke-width": 2 })) line.setAttribute(key, value);
  if (dash) line.setAttribute("stroke-dasharray", dash);
  svg.append(line);
  return svg;
}

function listItem(run, reason) {
  const item = document.createElement("li");
  item.dataset.drawn = String(!reason);
  item.title = run.document;
  const name = document.createElement("span");
  name.className = "pinned-label";
  name.textContent = run.label;
  const note = document.createElement("span");
  note.className = "pinned-note";
  note.textContent = reason ? `not drawn: ${reason}` : "drawn";
  const remove = document.createElement("button");
  remove.type = "button";
  remove.textContent = "Remove";
  remove.setAttribute("aria-label", `Remove ${run.label}`);
  remove.dataset.remove = String(run.id);
  item.append(swatch(run.color, run.dash), name, note, remove);
  return item;
}

// The series to plot for y against x of `view` (null: no curve): each kept run's whose
// quantities and units match, then the current run's unless it is kept itself; the list of
// kept runs shown with why each is or is not drawn.
export function overlaid(view, x, y) {
  const units = view ? { x: view.units[x] || "", y: view.units[y] || "" } : { x: "", y: "" };
  const drawable = view && view.series[x] && view.series[y];
  const reasons = kept.map((run) => whyNot(run, drawable ? x : "", drawable ? y : "", units));
  $("pinned-list").replaceChildren(...kept.map((run, k) => listItem(run, reasons[k])));
  $("compare").hidden = !kept.length;
  $("pin-curve").disabled = !view || Object.keys(view.series).length < 2 || isKept(view);
  $("pin-curve").textContent = isKept(view) ? "Kept for comparison" : "Keep for comparison";
  if (!drawable) return [];
  const shown = kept.filter((_, k) => !reasons[k]).map((run) => ({ name: run.label, x: run.view.series[x], y: run.view.series[y],
                                                                  color: run.color, dash: run.dash }));
  if (isKept(view)) return shown;
  const current = { name: shown.length ? `this run: ${runLabel(view.run)}` : seriesName(view, y), x: view.series[x], y: view.series[y], color: PALETTE[0] };
  return [current, ...shown];
}

// The kept runs as plain data (their labels and the series of their curves), for a test or a console.
export function keptRuns() {
  return kept.map((run) => ({ label: run.label, document: run.document, series: run.view.series, units: run.view.units }));
}

// The buttons: keep the current view, remove one, clear all; `rerender` draws the curve again.
export function wireCompare(currentView, rerender) {
  $("pin-curve").addEventListener("click", () => { if (keep(currentView())) rerender(); });
  $("clear-pinned").addEventListener("click", () => { kept.length = 0; rerender(); $("pin-curve").focus(); });
  $("pinned-list").addEventListener("click", (event) => {
    const button = event.target.closest("button[data-remove]");
    if (!button) return;
    const at = kept.findIndex((run) => String(run.id) === button.dataset.remove);
    if (at >= 0) kept.splice(at, 1);
    rerender();
    const next = $("pinned-list").querySelectorAll("button[data-remove]"); // focus stays in the list, else goes back to Keep
    (next[Math.min(at, next.length - 1)] || $("pin-curve")).focus();
  });
}
