// Views of job results (see results.js for the shape of a view): sweeps and contact paths as
// series per point, contact paths also as frames; simulations as the simulate analysis;
// anything else as a table of its numbers.

import { contactFrame } from "./contactframes.js";
import { fieldName, seriesLabel } from "./names.js";
import { lengthUnitOf, mostMoving, simulationView, withFieldLoads } from "./results.js";
import { recordsTable } from "./vibration.js";
import { numberText } from "./display.js";

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
    const frame = contactFrame(p, `${fieldName(field.path)} = ${numberText(+p.values[0])} ${field.unit}`, base, result.force_unit);
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

// What each function of an exported library computes and the arrays it takes and fills
// (the header's, service/export/templates/header.h.in), from the manifest's counts.
function exportedFunction(task, m) {
  const inputs = m.inputs.length, outputs = m.outputs.length, n = ((m.stiffness || {}).coordinates || []).length;
  const contact = ((m.contact || {}).outputs || []).length;
  const target = m.target || {};
  return {
    equilibrium: ["the equilibrium at the inputs", `in[${inputs}] → out[${outputs}]`],
    stiffness: ["the tangent stiffness at the equilibrium at the inputs", `in[${inputs}] → K[${n} × ${n}]`],
    target: [`the ${target.input} that brings ${target.output} to a goal [${target.unit}]`, `in[${inputs}], goal → value, out[${outputs}]`],
    contact: ["the contact state at the inputs", `in[${inputs}] → out[${contact}]`],
  }[task] || ["", ""];
}

// The Newton steps per call of a task, the worst the export measured over its example path.
function stepsOf(task, worst) {
  const warm = worst[`${task}_warm`], cold = worst[`${task}_cold`];
  if (warm !== undefined) return `${warm} from the last solution, ${cold} from rest`;
  return cold !== undefined && cold !== null ? `${cold} from rest` : "–";
}

// An export: its functions (what each computes, its arrays, the Newton steps per call the
// export measured), its inputs and outputs with their units, the archive's size. No time per
// call is measured on the server (nothing is compiled there): the archive's benchmark is.
function exportView(result) {
  const v = emptyView();
  const m = result && result.manifest;
  if (!m) { v.summary.push(["status", (result && result.status) || "pending"]); return v; }
  const worst = m.worst_case_iterations || {};
  const archive = result.archive || {};
  v.tables.push({ caption: `Functions (${m.header}); time per call: not measured here, nothing is compiled on the server (make, then ./bench, measures it)`,
                  columns: ["function", "computes", "arrays", "Newton steps per call (worst measured)"],
                  rows: m.tasks.map((task) => [`${m.name}_${task}`, ...exportedFunction(task, m), task === "stiffness" ? "the equilibrium's, then one kernel call" : stepsOf(task, worst)]) });
  const range = (i) => (i.low === null && i.high === null ? "any" : `${i.low_excluded ? "(" : "["}${i.low ?? "−∞"}, ${i.high ?? "∞"}]`);
  v.tables.push({ caption: "Inputs (in[], in this order)", columns: ["input", "field", "default", "range", "unit"],
                  rows: m.inputs.map((i) => [i.name, `${fieldName(i.pointer)} (${i.pointer})`, i.default, range(i), i.unit]) });
  v.tables.push({ caption: "Outputs (out[], in this order)", columns: ["output", "of the document", "unit"],
                  rows: m.outputs.map((o) => [o.name, o.output, o.unit]) });
  if (m.contact && m.contact.note) v.summary.push(["contact", m.contact.note]);
  v.summary.push(["status", result.status], ["archive", `${archive.file || ""}, ${archive.bytes ?? "–"} bytes, SHA-256 ${archive.sha256 || "–"}`],
                 ["unknowns", m.unknowns], ["steps measured over", worst.measured_over || "–"],
                 ["kernel calls per call, at most", (m.limits || {}).kernel_calls_per_call_at_most ?? "–"],
                 ["written in", `${m.export_seconds} s`], ["model", m.model], ["flexmech", m.flexmech], ["CasADi", m.casadi]);
  return v;
}

export function jobView(kind, result, drawing) {
  if (kind === "export") return exportView(result);
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
