// The result card's headline: per analysis and job kind, the one or two quantities an engineer
// reads first (the force that reaches a target, the first frequency, the peak contact force,
// the energy balance), named in words, with their units and four significant digits. Each
// reader takes the service's report (or a job's result) and returns
// {items: [{name, value, unit, note, id}], warnings: [...]}; the card (card.js) draws it.

import { fieldName } from "./names.js";
import { display } from "./display.js";
import { lengthUnitOf } from "./results.js";

// A value with its unit, in its display unit (display.js): "0.336 mm/uN", "1.21946 ug".
const quantity = (value, unit) => display(unit || "", [value]).text(value, true);

const finite = (x) => typeof x === "number" && Number.isFinite(x);

function largestBy(entries, size) {
  let best = null;
  for (const entry of entries) if (finite(size(entry)) && (!best || Math.abs(size(entry)) > Math.abs(size(best)))) best = entry;
  return best;
}

// The output that moves most, as a displacement ("end_effector.x moves -0.2575 mm").
function largestDisplacement(report) {
  const units = report.displacement_units || {};
  const lengths = Object.entries(report.displacements || {}).filter(([name]) => !/angle|theta/.test(name) && units[name]);
  const best = largestBy(lengths, ([, value]) => value);
  return best ? { name: `largest travel (${best[0]})`, value: best[1], unit: units[best[0]] } : null;
}

function equilibrium(report) {
  const items = [];
  const target = report.target;
  if (target) {
    const reaches = target.output ? `${target.output} = ${quantity(target.equals, target.output_unit)}` : "the target";
    items.push({ id: "target", name: fieldName(target.path), value: target.value, unit: target.unit,
                 note: target.status === "converged" ? `brings ${reaches} (${target.path})` : `target ${target.status.replace(/_/g, " ")}` });
  }
  const travel = largestDisplacement(report);
  if (travel) items.push(travel);
  else {  // nothing free to move (every body held): what holds it
    const units = report.output_units || {};
    const reactions = Object.entries(report.outputs || {}).filter(([name]) => /^reactions\..*\.F[xy]$/.test(name));
    const best = largestBy(reactions, ([, value]) => value);
    if (best) items.push({ name: `largest reaction (${best[0].replace(/^reactions\./, "")})`, value: best[1], unit: units[best[0]] || "" });
  }
  return items;
}

function trace(report) {
  const limits = report.limit_points || [];
  if (limits.length) {
    return limits.slice(0, 2).map((lp, k) => ({ name: `${k ? "second" : "first"} limit load (${lp.kind})`, value: lp.value, unit: report.unit,
                                             note: `${fieldName(report.path)}, after point ${lp.after_point}` }));
  }
  const values = report.values || [];
  return [{ name: `${fieldName(report.path)} reached`, value: values[values.length - 1], unit: report.unit, note: `${values.length} points, no limit point` }];
}

function contactItems(pairs, unit) {
  const forces = Object.entries(pairs || {}).map(([name, pair]) => [name, pair.normal_force]);
  const best = largestBy(forces, ([, force]) => force);
  if (!best) return [];
  const closed = Object.values(pairs).filter((pair) => pair.state && pair.state !== "open").length;
  return [{ name: "peak contact force", value: best[1], unit, note: `pair ${best[0]}; ${closed} of ${forces.length} pairs in contact` }];
}

function modes(report) {
  const elastic = (report.modes || []).filter((mode) => finite(mode.frequency) && mode.kind === "elastic");
  const items = elastic.slice(0, 2).map((mode, k) => ({ name: k ? "second frequency" : "first frequency", value: mode.frequency,
                                                       unit: (report.units || {}).frequency || "Hz", note: `mode ${mode.mode}` }));
  if (report.total_mass) items.push({ name: "moving mass", value: report.total_mass, unit: report.total_mass_unit });
  return items;
}

// A resonance's amplitude unit: its output's per the input's (the response's own unit).
const amplitudeUnit = (report, peak) => ((report.responses || {})[peak.output] || {}).unit || (report.units || {}).amplitude || "";

function frequencyResponse(report) {
  const peaks = report.resonances || [];
  const units = report.units || {};
  return peaks.slice(0, 2).map((peak, k) => ({ name: k ? "second resonance" : "first resonance", value: peak.frequency, unit: units.frequency || "Hz",
                                               note: finite(peak.amplitude) ? `amplitude ${quantity(peak.amplitude, amplitudeUnit(report, peak))}` : "" }));
}

function simulation(report) {
  const items = [];
  const units = report.units || {};
  if (finite(report.time_reached)) items.push({ name: "time reached", value: report.time_reached, unit: "s", note: finite(report.steps) ? `${report.steps} steps` : "" });
  if (finite(report.energy_balance_error)) items.push({ name: "energy balance error (relative)", value: 100 * report.energy_balance_error, unit: "%", note: "of the largest energy" });
  const accuracy = report.accuracy;
  if (accuracy && accuracy.estimated_errors) {  // a run to an accuracy target: its largest estimate and what it chose
    const worst = largestBy(Object.entries(accuracy.estimated_errors), ([, estimate]) => estimate);
    const elements = Object.entries(accuracy.intervals || {}).map(([name, n]) => `${name} ${n}`).join(", ");
    const steps = "step" in accuracy ? `step ${accuracy.step} s` : `tolerance ${accuracy.tolerance}`;
    if (worst) items.push({ name: `estimated error of ${worst[0]} (relative)`, value: worst[1], unit: "", note: `target ${accuracy.target} ${accuracy.met ? "met" : "not met"}; elements ${elements || "none"}; ${steps}` });
  }
  const impacts = report.impacts || [];
  if (impacts.length) {
    const peak = largestBy(impacts, (impact) => impact.peak_force);
    items.push({ name: "impacts", value: impacts.length, unit: "", note: peak ? `peak force ${quantity(peak.peak_force, units.force)}` : "" });
  }
  return items;
}

function sweep(result) {
  const points = result.points || [];
  const field = (result.parameters || [])[0];
  const last = points[points.length - 1];
  if (!field || !last) return [];
  const units = result.output_units || {};
  const until = result.until;
  const reached = until && finite(until.value);  // swept until an output reached a value: where it did
  const items = [reached
    ? { name: `${fieldName(until.path)} at ${until.output} = ${quantity(until.equals, units[until.output])}`, value: until.value, unit: until.unit, note: `${points.length} points` }
    : { name: `${fieldName(field.path)} at the last point`, value: last.values[0], unit: field.unit, note: `${points.length} points` }];
  const target = result.until && result.until.output;  // a sweep until an output reaches a value: that output
  const lengthUnit = lengthUnitOf(units);
  const changes = Object.keys(last.outputs || {}).filter((name) => units[name] === lengthUnit)
    .map((name) => [name, last.outputs[name] - ((points[0].outputs || {})[name] ?? 0)]);
  const moved = target && target in (last.outputs || {}) ? [target] : largestBy(changes, ([, change]) => change);
  if (moved && !reached) items.push({ name: `${moved[0]} there`, value: last.outputs[moved[0]], unit: units[moved[0]] || "" });
  return items;
}

function contactPath(result) {
  let best = null;
  for (const point of result.points || []) {
    for (const [name, pair] of Object.entries(point.pairs || {})) {
      if (finite(pair.normal_force) && (!best || pair.normal_force > best.force)) best = { name, force: pair.normal_force, at: point.values[0] };
    }
  }
  const field = (result.parameters || [])[0] || {};
  return best ? [{ name: "peak contact force", value: best.force, unit: result.force_unit, note: `pair ${best.name} at ${fieldName(field.path)} = ${quantity(best.at, field.unit)}` }] : [];
}

function optimization(result) {
  if (!result || !result.design) return [];
  const units = result.units || {};
  return [{ name: "objective at the optimum", value: result.objective, unit: units.objective || "", note: `${result.iterations ?? "–"} iterations` },
          ...Object.entries(result.design).slice(0, 2).map(([path, value]) => ({ name: fieldName(path), value, unit: units[path] || "" }))];
}

function impactStudy(result) {
  const ranking = result.ranking || [];
  return ranking.length ? [{ name: "fields ranked", value: ranking.length, unit: "", note: `earliest departure: ${ranking[0].field ?? Object.values(ranking[0])[0]}` }] : [];
}

// An export: the archive's size and the Newton steps per call the export measured (the time
// per call is not measured on the server: the archive's benchmark measures it).
function exported(result) {
  const m = result.manifest, archive = result.archive || {};
  if (!m) return [];
  const worst = m.worst_case_iterations || {};
  return [{ name: "archive", value: archive.bytes / 1000, unit: "kB", note: `${m.tasks.length} functions, ${m.inputs.length} inputs, ${m.outputs.length} outputs` },
          { name: "Newton steps per call, worst measured", value: worst.equilibrium_warm, unit: "", note: `equilibrium from the last solution; time per call: ./bench of the archive` }];
}

// A tolerance analysis: the yield against the specs, and the scatter of the responses the specs
// bound (else of the first ones).
function tolerance(result) {
  const found = result.yield, responses = Object.entries(result.responses || {}).sort(([, a], [, b]) => Boolean(b.spec) - Boolean(a.spec));
  const items = found ? [{ name: "yield", value: 100 * found.monte_carlo, unit: "%", note: `of ${found.samples} samples, first order ${(100 * found.first_order).toFixed(1)} %` }] : [];
  for (const [name, entry] of responses.slice(0, 2)) items.push({ name: `${name} standard deviation`, value: entry.first_order.std, unit: entry.unit, note: `nominal ${quantity(entry.nominal, entry.unit)}` });
  return items;
}

const READERS = {
  "solve:equilibrium": equilibrium,
  "solve:linearization": equilibrium,
  "solve:energy": (r) => [...equilibrium(r), ...(finite(r.energy) ? [{ name: "strain energy", value: r.energy, unit: r.energy_unit || "" }] : [])],
  "solve:inverse": equilibrium,
  "solve:trace": trace,
  "solve:contact": (r) => [...contactItems(r.pairs, (r.units || {}).force), ...equilibrium(r)],
  "solve:modes": modes,
  "solve:frequency_response": frequencyResponse,
  "solve:tolerance": tolerance,
  "solve:simulate": simulation,
  "job:simulation": simulation,
  "job:sweep": sweep,
  "job:contact": contactPath,
  "job:optimize": optimization,
  "job:impact_study": impactStudy,
  "job:export": exported,
};

// The headline of a result: `source` is "solve:<analysis>" or "job:<kind>".
export function headline(source, result) {
  const read = READERS[source];
  const items = (read && result ? read(result) : []).filter((item) => item && finite(item.value));
  return { items, warnings: (result && result.warnings) || [] };
}
