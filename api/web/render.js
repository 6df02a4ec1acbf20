// A view (results.js) into the page: the summary and tables of the Outputs tab, curves of any
// series against any other (with the runs kept for comparison), energies against time, and CSV
// of what is shown.

import { overlaid } from "./compare.js";
import { seriesLabel, seriesName } from "./names.js";
import { exactText, numberText, shownTable } from "./display.js";
import { linePlot } from "./plot.js";

const $ = (id) => document.getElementById(id);

// A cell: a number as display.js shows it (its exact value in the title), else the text.
function cell(row, value, header = false, exact = null) {
  const element = document.createElement(header ? "th" : "td");
  if (exact !== null) { element.textContent = value; element.className = "number"; element.title = String(exact); }
  else element.textContent = value === null || value === undefined ? "–" : String(value);
  row.append(element);
}

function tableOf(table) {
  const { caption, rows } = table;
  const shown = shownTable(table);
  const element = document.createElement("table");
  element.createCaption().textContent = caption;
  const head = element.createTHead().insertRow();
  for (const column of shown.columns) { cell(head, column, true); head.lastChild.scope = "col"; }
  const body = element.createTBody();
  rows.forEach((values, r) => {
    const row = body.insertRow();
    values.forEach((value, i) => cell(row, shown.rows[r][i], i === 0 && table.columns[0] !== "point", shown.numeric[r][i] ? value : null));
    if (typeof values[0] === "string") row.dataset.name = values[0];
  });
  return element;
}

function summaryOf(v) {
  const list = document.createElement("dl");
  list.className = "summary";
  for (const [term, detail] of v.summary) {
    const dt = document.createElement("dt"), dd = document.createElement("dd");
    dt.textContent = term;
    dd.textContent = typeof detail !== "number" ? String(detail) : /residual|tolerance/.test(term) ? exactText(detail) : numberText(detail);
    if (term === "status") dd.className = ["converged", "finished", "succeeded"].includes(detail) ? "status-ok" : "status-bad";
    list.append(dt, dd);
  }
  return list;
}

// The tables, then the run's diagnostics folded (status, iterations, residuals: the result card
// above has the headline and the warnings).
export function renderTables(v) {
  const panel = $("panel-table");
  panel.replaceChildren();
  for (const table of v.tables) if (table && table.rows.length) panel.append(tableOf(table));
  for (const chart of v.charts || []) panel.append(chart()); // an analysis' own figures (tolerances.js)
  if (v.summary.length) {
    const folded = document.createElement("details");
    folded.className = "diagnostics";
    const title = document.createElement("summary");
    title.textContent = "Diagnostics";
    folded.append(title, summaryOf(v));
    panel.append(folded);
  }
}

// A CSV header keeps the series' exact key (a field's pointer) with its unit.
function exactLabel(v, name) {
  return v.units[name] ? `${name} [${v.units[name]}]` : name;
}

// Whether the series is drawn on a log axis (a view's `logScale`: frequencies).
const logScaled = (v, name) => Boolean(v.logScale && v.logScale.includes(name));

export function fillCurveChoices(v) {
  const names = Object.keys(v.series);
  for (const [select, index] of [[$("curve-x"), 0], [$("curve-y"), 1]]) {
    select.replaceChildren(...names.map((name) => new Option(seriesLabel(v, name), name)));
    const chosen = v.defaultCurve ? v.defaultCurve[index] : names[index] ?? names[0];
    if (chosen !== undefined) select.value = chosen;
  }
  $("tab-curves").disabled = names.length < 2;
}

// The curve of y against x, with the runs kept for comparison (compare.js) on the same axes.
export function renderCurve(v) {
  const x = $("curve-x").value, y = $("curve-y").value;
  const box = $("curve");
  const series = overlaid(v, x, y);
  if (!series.length) { box.replaceChildren(); return null; }
  const svg = linePlot({ series, xLabel: seriesLabel(v, x), yLabel: seriesLabel(v, y), xLog: logScaled(v, x), yLog: logScaled(v, y),
                         title: `${seriesName(v, y)} against ${seriesName(v, x)}`, points: Math.max(...series.map((s) => s.x.length)) <= 60 });
  box.replaceChildren(svg);
  return svg;
}

export function renderEnergies(v) {
  const box = $("energy-plot");
  $("tab-energies").disabled = !v || !v.energies;
  if (!v || !v.energies) { box.replaceChildren(); return null; }
  const { time, series, unit } = v.energies;
  const svg = linePlot({ series: Object.entries(series).map(([name, values]) => ({ name, x: time, y: values })),
                         xLabel: "time [s]", yLabel: `energy [${unit}]`, title: "Energies and works" });
  box.replaceChildren(svg);
  return svg;
}

const quote = (value) => (typeof value === "string" && /[",\n]/.test(value) ? `"${value.replace(/"/g, '""')}"` : value ?? "");

// The series as columns (one row per state), else the first table.
export function csvOf(v) {
  const names = Object.keys(v.series);
  if (names.length) {
    const rows = v.series[names[0]].map((_, i) => names.map((n) => quote(v.series[n][i])).join(","));
    return [names.map((n) => quote(exactLabel(v, n))).join(","), ...rows].join("\n") + "\n";
  }
  const table = v.tables.find((t) => t && t.rows.length);
  if (!table) return "";
  return [table.columns.map(quote).join(","), ...table.rows.map((r) => r.map(quote).join(","))].join("\n") + "\n";
}
