// Results as the page shows them, whatever produced them: a summary, tables, named series of
// equal length (curves of any one against any other), energies against time, and frames for
// the animation (element centre lines and body poses per state, see scene.js).

import { contactFrame } from "./contactframes.js";
import { fieldName } from "./names.js";
import { posesAtElementEnds } from "./scene.js";
import { toleranceView } from "./tolerances.js";
import { modeFrames, modesTable, recordsTable, responseSeries } from "./vibration.js";
import { display, exactText, numberText } from "./display.js";

const MAX_IMPACT_ROWS = 200;
const isNumberList = (value) => Array.isArray(value) && value.length > 0 && value.every((v) => v === null || typeof v === "number");

function view() {
  return { summary: [], tables: [], series: {}, units: {}, defaultCurve: null, energies: null, frames: [], frameUnit: "", openAt: null };
}

function outputsTable(caption, values, units) {
  const rows = Object.entries(values || {}).filter(([, v]) => v === null || typeof v === "number").map(([name, v]) => [name, v, (units || {})[name] || ""]);
  return rows.length ? { caption, columns: ["output", "value", "unit"], rows } : null;
}

function solveView(report) {
  const v = view();
  v.summary.push(["status", report.status], ["analysis", report.analysis]);
  if (report.message) v.summary.push(["message", report.message]);
  if (report.iterations) v.summary.push(["iterations", report.iterations]);
  if (report.residual_norm !== null && report.residual_norm !== undefined) v.summary.push(["largest unbalanced force", quantity(report.residual_norm, report.residual_unit, true)]);
  if (report.residual_moment !== null && report.residual_moment !== undefined) v.summary.push(["largest unbalanced moment", quantity(report.residual_moment, report.residual_moment_unit, true)]);
  v.tables.push(outputsTable("Outputs", report.outputs, report.output_units), outputsTable("Displacements", report.displacements, report.displacement_units));
  if (report.pairs) {
    const u = report.units || {};
    v.tables.push({ caption: "Contact pairs", columns: ["pair", "state", `normal force [${u.force}]`, `friction force [${u.force}]`, `point [${u.length}]`, `gap [${u.length}]`],
                    rows: Object.entries(report.pairs).map(([name, p]) => [name, p.state, p.normal_force, p.friction_force, p.point ? p.point.map((x) => +x.toPrecision(6)).join(", ") : "–", p.gap]) });
  }
  if (report.wrenches) {
    const units = report.wrench_units || {};
    v.tables.push({ caption: "Wrenches", columns: ["on", `Fx [${units.Fx || ""}]`, `Fy [${units.Fy || ""}]`, `M [${units.M || ""}]`],
                    rows: Object.entries(report.wrenches).map(([name, w]) => [name, w.Fx, w.Fy, w.M]) });
  }
  for (const [key, value] of Object.entries(report)) {  // an analysis' own numbers (a plugin's too)
    if (typeof value === "number" && !SHOWN_NUMBERS.has(key)) v.summary.push([key.replace(/_/g, " "), quantity(value, report[`${key}_unit`] ?? UNITS_OF[key] ?? "", /residual|tolerance/.test(key))]);
  }
  if (report.stiffness && report.stiffness.coordinates) {
    const k = report.stiffness;
    const per = (unit) => (unit ? `per ${unit}` : "per unit");
    v.tables.push({ caption: "Tangent stiffness K_T (a row's force or moment per a column's displacement)",
                    columns: ["row [unit]", ...k.coordinates.map((c, j) => `${c} [${per((k.column_units || [])[j])}]`)],
                    rows: k.K.map((row, i) => [`${k.coordinates[i]} [${k.row_units[i]}]`, ...row]) });
  }
  return v;
}

// Numbers of a report the view shows in its own way (or not at all), and the units of the
// rest that carry none of their own (a count, a ratio: "1").
const SHOWN_NUMBERS = new Set(["iterations", "residual_norm", "residual_moment"]);
const UNITS_OF = { seconds: "s", solver_residual: "1", kkt_residual: "1", approach_steps: "1", unknowns: "1", available: "1",
                   time_reached: "s", step: "s", energy_balance_error: "1", trial_steps: "1", steps: "1", rescued_steps: "1",
                   damping: "1/s", clearance: "" };

// A number with its unit in its display unit (display.js: "1.21946 ug", "4.77266 nJ"); a
// residual or a tolerance exactly, four digits ("4.698e-13 uN").
export function quantity(value, unit, exactly = false) {
  const shownUnit = unit && unit !== "1" ? unit : "";
  if (exactly) return `${exactText(value)}${shownUnit ? ` ${shownUnit}` : ""}`;
  return display(shownUnit, [value]).text(value, true);
}

export function simulationView(report, drawing) {
  const v = view();
  v.summary.push(["status", report.status], ["message", report.message || "–"], ["reached", quantity(report.time_reached, "s")], ["steps", report.steps ?? "–"]);
  if (typeof report.energy_balance_error === "number") v.summary.push(["energy balance error (relative)", `${numberText(100 * report.energy_balance_error)} % of the largest energy`]);
  const times = report.times || [];
  v.series.time = times; v.units.time = "s";
  for (const [name, values] of Object.entries(report.outputs || {})) if (isNumberList(values)) { v.series[name] = values; v.units[name] = (report.output_units || {})[name] || ""; }
  const units = report.series_units || {};
  for (const [name, values] of Object.entries(report.coordinates || {})) { v.series[name] = values; v.units[name] = units[name] || (name.endsWith(".theta") ? report.units.angle : report.units.length); }
  for (const [pair, values] of Object.entries(report.contacts || {})) for (const [name, list] of Object.entries(values)) if (isNumberList(list)) { v.series[`${pair}.${name}`] = list; v.units[`${pair}.${name}`] = units[`${pair}.${name}`] || ""; }
  for (const group of ["constraint_forces", "motion_forces"]) {
    for (const [name, values] of Object.entries(report[group] || {})) if (isNumberList(values)) { v.series[name] = values; v.units[name] = units[name] || ""; }
  }
  const moving = mostMoving(v, [...Object.keys(report.outputs || {}), ...Object.keys(report.coordinates || {})], (report.units || {}).length);
  v.defaultCurve = moving ? ["time", moving] : null;
  if (report.energies) v.energies = { time: times, series: report.energies, unit: (report.units || {}).energy || "" };
  v.frames = simulationFrames(report, drawing);
  v.frameUnit = "s";
  const impacts = report.impacts || [];
  if (impacts.length) {
    const shown = impacts.slice(0, MAX_IMPACT_ROWS);
    const caption = shown.length < impacts.length ? `Impacts (the first ${shown.length}; ${impacts.length - shown.length} more in the JSON)` : "Impacts";
    v.tables.push(recordsTable(caption, shown, report.event_units || {}));
  }
  v.tables.push(lastValues(v));
  return v;
}

// The length unit of a set of outputs: that of any coordinate output (a point's x or y).
export function lengthUnitOf(units) {
  return units[Object.keys(units).find((name) => /\.(x|y)$/.test(name))];
}

// The series that moves most over the run, of `names`: lengths (`lengthUnit`) before others,
// user-named points before the bodies' and elements' own outputs; null if none moves.
export function mostMoving(v, names, lengthUnit) {
  let best = null, bestScore = [-1, -1, 0];
  for (const name of names) {
    const values = (v.series[name] || []).filter((x) => typeof x === "number" && Number.isFinite(x));
    if (values.length < 2) continue;
    const range = Math.max(...values) - Math.min(...values);
    if (!(range > 0)) continue;
    const score = [v.units[name] === lengthUnit ? 1 : 0, /^(bodies|elements)\./.test(name) ? 0 : 1, range];
    const better = score[0] !== bestScore[0] ? score[0] > bestScore[0] : score[1] !== bestScore[1] ? score[1] > bestScore[1] : score[2] > bestScore[2];
    if (better) { best = name; bestScore = score; }
  }
  return best;
}

function lastValues(v) {
  const rows = Object.entries(v.series).map(([name, list]) => [name, list[list.length - 1], v.units[name] || ""]);
  return { caption: "At the last state", columns: ["quantity", "value", "unit"], rows };
}

// Frames of a simulation: element centre lines from `shapes` (link dynamics) with each body
// where its elements end; rigid bodies from `coordinates` (impacts), flexures blended
// between the motions of their two bodies.
function simulationFrames(report, drawing) {
  const times = report.times || [];
  if (!drawing) return [];
  if (report.shapes && report.shapes.length) {
    const loads = loadsAlong((report.varying || {}).values || {}, drawing);
    return report.shapes.map((shape, k) => {
      const elements = Object.fromEntries(Object.entries(shape).map(([name, [xs, ys]]) => [name, xs.map((x, i) => [x, ys[i]])]));
      return { elements, poses: posesAtElementEnds(drawing, elements), about: "reference", label: `t = ${+(+times[k]).toPrecision(4)} s`,
               time: times[k], loads: loads.at(k), largestLoad: loads.largest };
    });
  }
  if (report.coordinates) {
    const rad = drawing.radians_per_angle_unit;
    return times.map((t, k) => {
      const poses = {};
      for (const name of Object.keys(drawing.bodies)) {
        const x = report.coordinates[`${name}.x`];
        if (x) poses[name] = [x[k], report.coordinates[`${name}.y`][k], report.coordinates[`${name}.theta`][k] * rad];
      }
      return { poses, about: "centre", blend: true, label: `t = ${+(+t).toPrecision(4)} s`, time: t };
    });
  }
  return [];
}

// The loads as frames draw them when some of their fields take a value per frame (a history's
// values at each kept state, a swept or traced field's value at each state): `values` maps a
// field's pointer (/loads/<name>/force/<0|1>, /loads/<name>/moment) to its values, one per
// frame. at(k) gives {name: {vector} or {value}} of frame k, the other fields as drawn;
// `largest` is the largest force over the frames, drawn or varying, so arrows keep one scale.
export function loadsAlong(values, drawing) {
  const given = (pointer) => Array.isArray(values[pointer]) && values[pointer].length > 0;
  const varying = drawing.loads.filter((l) => (l.kind === "force" ? [0, 1].some((i) => given(`/loads/${l.name}/force/${i}`)) : given(`/loads/${l.name}/moment`)));
  const component = (l, i, k) => (given(`/loads/${l.name}/force/${i}`) ? values[`/loads/${l.name}/force/${i}`][k] ?? l.vector[i] : l.vector[i]);
  const at = (k) => {
    if (!varying.length) return undefined;
    return Object.fromEntries(varying.map((l) => [l.name, l.kind === "force"
      ? { vector: [0, 1].map((i) => component(l, i, k)) }
      : { value: values[`/loads/${l.name}/moment`][k] }]));
  };
  let largest = Math.max(0, ...drawing.loads.filter((l) => l.kind === "force" && !varying.includes(l)).map((l) => Math.hypot(...l.vector)));
  for (const l of varying.filter((l) => l.kind === "force")) {
    const count = Math.max(...[0, 1].map((i) => (given(`/loads/${l.name}/force/${i}`) ? values[`/loads/${l.name}/force/${i}`].length : 0)));
    for (let k = 0; k < count; k += 1) largest = Math.max(largest, Math.hypot(component(l, 0, k), component(l, 1, k)));
  }
  return { at, largest: largest || undefined };
}

// Frames of states along a field (a sweep's, a trace's, a contact path's), each given the
// loads at its own value of the field (`values`, one per frame): a swept load is drawn at
// the frame's value, not at the document's.
export function withFieldLoads(frames, drawing, pointer, values) {
  if (!drawing || !pointer) return frames;
  const loads = loadsAlong({ [pointer]: values }, drawing);
  return frames.map((frame, k) => ({ ...frame, loads: loads.at(k), largestLoad: loads.largest }));
}

function traceView(report, drawing) {
  const v = view();
  v.summary.push(["status", report.status], ["message", report.message || ""]);
  const field = report.path || "field";
  v.series[field] = report.values || []; v.units[field] = report.unit || "";
  for (const [name, values] of Object.entries(report.outputs || {})) if (isNumberList(values)) { v.series[name] = values; v.units[name] = (report.output_units || {})[name] || ""; }
  // against a point's displacement where there is one (as `flexmech trace` shows it), else
  // against the first output that moves
  const moving = Object.keys(v.series).filter((n) => n !== field && new Set(v.series[n]).size > 1);
  const first = moving.find((n) => n.endsWith(".dy")) || moving[0];
  v.defaultCurve = first ? [first, field] : null;
  const frames = (report.frames || []).map((f) => ({ elements: f.elements, poses: f.poses, about: "reference", stresses: f.stresses,
                                                     label: `${fieldName(field)} = ${numberText(+f.value)} ${report.unit || ""} (point ${f.point})` }));
  v.frames = withFieldLoads(frames, drawing, report.path, (report.frames || []).map((f) => f.value));
  v.frameUnit = report.unit || "";
  if (report.limit_points && report.limit_points.length) {
    v.tables.push({ caption: "Limit points", columns: ["kind", `${fieldName(field)} [${report.unit || ""}]`, "after point"], rows: report.limit_points.map((lp) => [lp.kind, lp.value, lp.after_point]) });
  }
  return v;
}

export function resultView(kind, result, drawing) {
  if (kind !== "solve") return null;
  if (result.analysis === "simulate") return simulationView(result, drawing);
  if (result.analysis === "trace") return traceView(result, drawing);
  const v = solveView(result);
  if (result.analysis === "modes") {
    v.tables.push(modesTable(result));
    v.frames = modeFrames(result);
    v.openAt = 0; // the first mode, at rest
    return v;
  }
  if (result.analysis === "frequency_response") {
    responseSeries(v, result);
    return v;
  }
  if (result.analysis === "tolerance") return toleranceView(v, result);
  for (const [key, value] of Object.entries(result)) {  // an analysis' own lists of records (a plugin's too)
    if (Array.isArray(value) && value.length && value.every((row) => row && typeof row === "object" && !Array.isArray(row))) v.tables.push(recordsTable(key, value, result.units || {}));
  }
  if (result.drawing && drawing) v.frames = [contactFrame(result, `contact: ${result.status}`, drawing, (result.units || {}).force)]; // the contact state
  return v;
}
