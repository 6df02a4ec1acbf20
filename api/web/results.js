// Results as the page shows them, whatever produced them: a summary, tables, named series of
// equal length (curves of any one against any other), energies against time, and frames for
// the animation (element centre lines and body poses per state, see scene.js).

import { contactFrame } from "./contactframes.js";
import { posesAtElementEnds } from "./scene.js";
import { modeFrames, modesTable, recordsTable, responseSeries } from "./vibration.js";

const isNumberList = (value) => Array.isArray(value) && value.length > 0 && value.every((v) => v === null || typeof v === "number");

function view() {
  return { summary: [], tables: [], series: {}, units: {}, defaultCurve: null, energies: null, frames: [], frameUnit: "" };
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
  if (report.residual_norm !== null && report.residual_norm !== undefined) v.summary.push(["largest unbalanced force", `${report.residual_norm} ${report.residual_unit || ""}`]);
  if (report.target) v.target = report.target;
  for (const warning of report.warnings || []) v.summary.push(["warning", warning]);
  v.tables.push(outputsTable("Outputs", report.outputs, report.output_units), outputsTable("Displacements", report.displacements, report.displacement_units));
  if (report.pairs) {
    v.tables.push({ caption: `Contact pairs (${(report.units || {}).force || ""})`, columns: ["pair", "state", "normal force", "friction force", "point", "gap"],
                    rows: Object.entries(report.pairs).map(([name, p]) => [name, p.state, p.normal_force, p.friction_force, p.point ? p.point.map((x) => +x.toPrecision(6)).join(", ") : "–", p.gap]) });
  }
  if (report.wrenches) {
    const units = report.wrench_units || {};
    v.tables.push({ caption: "Wrenches", columns: ["on", `Fx [${units.Fx || ""}]`, `Fy [${units.Fy || ""}]`, `M [${units.M || ""}]`],
                    rows: Object.entries(report.wrenches).map(([name, w]) => [name, w.Fx, w.Fy, w.M]) });
  }
  for (const [key, value] of Object.entries(report)) {  // an analysis' own numbers (a plugin's too)
    if (typeof value === "number" && !SHOWN_NUMBERS.has(key)) v.summary.push([key.replace(/_/g, " "), `${value} ${report[`${key}_unit`] || ""}`.trim()]);
  }
  if (report.stiffness && report.stiffness.coordinates) {
    const k = report.stiffness;
    v.tables.push({ caption: "Tangent stiffness K_T", columns: ["", ...k.coordinates], rows: k.K.map((row, i) => [`${k.coordinates[i]} [${k.row_units[i]}]`, ...row]) });
  }
  return v;
}

// Numbers of a report the view shows in its own way (or not at all).
const SHOWN_NUMBERS = new Set(["iterations", "residual_norm", "residual_moment", "solver_residual"]);

export function simulationView(report, drawing) {
  const v = view();
  v.summary.push(["status", report.status], ["message", report.message || ""], ["reached", `${report.time_reached} s`], ["steps", report.steps]);
  if (report.energy_balance_error !== undefined) v.summary.push(["energy balance error", report.energy_balance_error]);
  const times = report.times || [];
  v.series.time = times; v.units.time = "s";
  for (const [name, values] of Object.entries(report.outputs || {})) if (isNumberList(values)) { v.series[name] = values; v.units[name] = (report.output_units || {})[name] || ""; }
  for (const [name, values] of Object.entries(report.coordinates || {})) { v.series[name] = values; v.units[name] = name.endsWith(".theta") ? report.units.angle : report.units.length; }
  for (const [pair, values] of Object.entries(report.contacts || {})) for (const [name, list] of Object.entries(values)) if (isNumberList(list)) { v.series[`${pair}.${name}`] = list; }
  for (const [name, values] of Object.entries(report.constraint_forces || {})) if (isNumberList(values)) v.series[name] = values;
  const names = Object.keys(v.series).filter((n) => n !== "time");
  v.defaultCurve = names.length ? ["time", names[0]] : null;
  if (report.energies) v.energies = { time: times, series: report.energies, unit: (report.units || {}).energy || "" };
  v.frames = simulationFrames(report, drawing);
  v.frameUnit = "s";
  if (report.impacts && report.impacts.length) {
    v.tables.push({ caption: "Impacts", columns: Object.keys(report.impacts[0]), rows: report.impacts.slice(0, 200).map((i) => Object.values(i).map((x) => (typeof x === "object" ? JSON.stringify(x) : x))) });
  }
  v.tables.push(lastValues(v));
  return v;
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
    return report.shapes.map((shape, k) => {
      const elements = Object.fromEntries(Object.entries(shape).map(([name, [xs, ys]]) => [name, xs.map((x, i) => [x, ys[i]])]));
      return { elements, poses: posesAtElementEnds(drawing, elements), about: "reference", label: `t = ${+(+times[k]).toPrecision(4)} s` };
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
      return { poses, about: "centre", blend: true, label: `t = ${+(+t).toPrecision(4)} s` };
    });
  }
  return [];
}

function traceView(report) {
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
  v.frames = (report.frames || []).map((f) => ({ elements: f.elements, poses: f.poses, about: "reference",
                                                 label: `${field} = ${+(+f.value).toPrecision(5)} ${report.unit || ""} (point ${f.point})` }));
  v.frameUnit = report.unit || "";
  if (report.limit_points && report.limit_points.length) {
    v.tables.push({ caption: "Limit points", columns: ["kind", field, "after point"], rows: report.limit_points.map((lp) => [lp.kind, lp.value, lp.after_point]) });
  }
  return v;
}

export function resultView(kind, result, drawing) {
  if (kind !== "solve") return null;
  if (result.analysis === "simulate") return simulationView(result, drawing);
  if (result.analysis === "trace") return traceView(result);
  const v = solveView(result);
  if (result.analysis === "modes") {
    v.tables.push(modesTable(result));
    v.frames = modeFrames(result);
    return v;
  }
  if (result.analysis === "frequency_response") {
    responseSeries(v, result);
    return v;
  }
  for (const [key, value] of Object.entries(result)) {  // an analysis' own lists of records (a plugin's too)
    if (Array.isArray(value) && value.length && value.every((row) => row && typeof row === "object" && !Array.isArray(row))) v.tables.push(recordsTable(key, value, result.units || {}));
  }
  if (result.drawing && drawing) v.frames = [contactFrame(result, `contact: ${result.status}`, drawing, (result.units || {}).force)]; // the contact state
  return v;
}
