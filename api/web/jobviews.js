// Views of job results (see results.js for the shape of a view): sweeps and contact paths as
// series per point, contact paths also as frames; simulations as the simulate analysis;
// anything else as a table of its numbers.

import { contactFrame } from "./contactframes.js";
import { fieldName, seriesLabel } from "./names.js";
import { lengthUnitOf, mostMoving, simulationView, withFieldLoads } from "./results.js";
import { recordsTable } from "./vibration.js";

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
  const output = mostMoving(v, [...outputs], lengthUnitOf(result.output_units || {})) || [...outputs][0];
  v.defaultCurve = first && output ? [first.path, output] : null;
}

function pointsTable(caption, v, points) {
  const names = Object.keys(v.series);
  const rows = points.slice(0, MAX_TABLE_ROWS).map((p, i) => [p.index ?? i, p.status, ...names.map((n) => v.series[n][i])]);
  return { caption, columns: ["point", "status", ...names.map((n) => seriesLabel(v, n))], rows };
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
  const frames = points.map((p) => {
    const frame = contactFrame(p, `${fieldName(field.path)} = ${+(+p.values[0]).toPrecision(6)} ${field.unit}`, base, result.force_unit);
    frame.overlay.largestForce = largest;
    return frame;
  });
  v.frames = withFieldLoads(frames, base, field.path, points.map((p) => p.values[0]));
  v.frameUnit = field.unit;
  return v;
}

// Every number of a result with its unit: its sibling "<name>_unit" (a studied field's
// change), else the report's `units` by the field's last name; "?" where the report names none.
function numbersTable(caption, data) {
  const rows = [];
  const units = (data && data.units) || {};
  const walk = (value, path, key, unit) => {
    if (rows.length >= MAX_TABLE_ROWS || key === "units" || key.endsWith("_unit")) return;
    if (value === null || typeof value !== "object") rows.push([path || "(value)", value, typeof value === "number" ? unit || units[key] || "?" : ""]);
    else for (const [inner, entry] of Object.entries(value)) walk(entry, path ? `${path}.${inner}` : inner, inner, value[`${inner}_unit`]);
  };
  walk(data, "", "", "");
  return { caption, columns: ["field", "value", "unit"], rows };
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
  Object.assign(v.units, { iteration: "1", constraint_violation: "1", dual_infeasibility: "1" }); // IPOPT's scaled measures
  v.units.objective = units.objective || "1";
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
    v.tables.push(recordsTable("Fields ranked by their earliest departure", result.ranking, { ...(result.units || {}), departure: "s", time: "s" }));
  }
  v.tables.push(numbersTable("Result", result));
  return v;
}
