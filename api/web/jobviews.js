// Views of job results (see results.js for the shape of a view): sweeps and contact paths as
// series per point, contact paths also as frames; simulations as the simulate analysis;
// anything else as a table of its numbers.

import { contactFrame } from "./contactframes.js";
import { simulationView } from "./results.js";

const MAX_TABLE_ROWS = 500;

function emptyView() {
  return { summary: [], tables: [], series: {}, units: {}, defaultCurve: null, energies: null, frames: [], frameUnit: "" };
}

function pointSeries(v, result, points) {
  for (const [k, parameter] of (result.parameters || []).entries()) {
    v.series[parameter.path] = points.map((p) => p.values[k]);
    v.units[parameter.path] = parameter.unit;
  }
  const outputs = new Set(points.flatMap((p) => Object.keys(p.outputs || {})));
  for (const name of outputs) {
    v.series[name] = points.map((p) => (p.outputs || {})[name] ?? null);
    v.units[name] = (result.output_units || {})[name] || "";
  }
  const first = (result.parameters || [])[0];
  const output = [...outputs][0];
  v.defaultCurve = first && output ? [first.path, output] : null;
}

function pointsTable(caption, v, points) {
  const names = Object.keys(v.series);
  const rows = points.slice(0, MAX_TABLE_ROWS).map((p, i) => [p.index ?? i, p.status, ...names.map((n) => v.series[n][i])]);
  return { caption, columns: ["point", "status", ...names.map((n) => (v.units[n] ? `${n} [${v.units[n]}]` : n))], rows };
}

function sweepView(result) {
  const v = emptyView();
  const points = result.points || [];
  const failed = points.filter((p) => p.status !== "converged").length;
  v.summary.push(["points", points.length], ["not converged", failed]);
  if (result.analysis) v.summary.push(["analysis", result.analysis]);
  pointSeries(v, result, points);
  v.tables.push(pointsTable("Points", v, points));
  return v;
}

function contactView(result, base) {
  const v = sweepView(result);
  const points = result.points || [];
  for (const pair of new Set(points.flatMap((p) => Object.keys(p.pairs || {})))) {
    v.series[`${pair}.normal_force`] = points.map((p) => ((p.pairs || {})[pair] || {}).normal_force ?? null);
    v.units[`${pair}.normal_force`] = result.force_unit;
  }
  const field = (result.parameters || [])[0] || { path: "", unit: "" };
  const largest = Math.max(0, ...points.flatMap((p) => Object.values(p.pairs || {}).map((q) => Math.hypot(...(q.force || [0, 0])))));
  v.frames = points.map((p, i) => {
    const frame = contactFrame(p, `${field.path} = ${+(+p.values[0]).toPrecision(6)} ${field.unit}`, base, result.force_unit);
    frame.overlay.largestForce = largest;
    return frame;
  });
  v.frameUnit = field.unit;
  return v;
}

function numbersTable(caption, data) {
  const rows = [];
  const walk = (value, path) => {
    if (rows.length >= MAX_TABLE_ROWS) return;
    if (value === null || typeof value !== "object") rows.push([path || "(value)", value]);
    else for (const [key, inner] of Object.entries(value)) walk(inner, path ? `${path}.${key}` : key);
  };
  walk(data, "");
  return { caption, columns: ["field", "value"], rows };
}

// An optimization: the design at its start and its optimum, and the iterations as curves.
function optimizeView(result) {
  const v = emptyView();
  v.summary.push(["status", result.status], ["IPOPT", result.ipopt_status || ""], ["iterations", result.iterations ?? "–"],
                 ["objective", result.objective]);
  if (result.message) v.summary.push(["message", result.message]);
  const units = result.units || {};
  v.tables.push({ caption: "Design", columns: ["field", "start", "optimum", "unit"],
                  rows: Object.entries(result.design || {}).map(([path, value]) => [path, (result.design_start || {})[path], value, units[path] || ""]) });
  const history = result.history || [];
  for (const name of ["iteration", "objective", "constraint_violation", "dual_infeasibility"]) v.series[name] = history.map((h) => h[name] ?? null);
  v.units.objective = units.objective || "";
  v.defaultCurve = history.length ? ["iteration", "objective"] : null;
  v.design = result.design || null;
  return v;
}

export function jobView(kind, result, drawing) {
  if (kind === "optimize" && result && result.design) return optimizeView(result);
  if (kind === "sweep") return sweepView(result);
  if (kind === "contact") return contactView(result, drawing);
  if (kind === "simulation") return simulationView(result, drawing);
  const v = emptyView();
  if (result && result.status) v.summary.push(["status", result.status]);
  if (kind === "impact_study" && result.ranking) {
    v.tables.push({ caption: "Fields ranked by their earliest departure", columns: Object.keys(result.ranking[0] || { field: 0 }),
                    rows: result.ranking.map((r) => Object.values(r).map((x) => (typeof x === "object" ? JSON.stringify(x) : x))) });
  }
  v.tables.push(numbersTable("Result", result));
  return v;
}
