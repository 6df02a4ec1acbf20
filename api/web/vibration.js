// The vibration analyses as the page shows them: the modes' table and each mode swinging in the
// drawing (frames of the centre lines the report moves along the mode), and a frequency
// response's curves (amplitude in dB against the frequency on a log axis, by default) with its
// resonances' table. A report's lists of records become tables as the CLI prints them.

const SWING_FRAMES = 24; // frames of one mode's period
const SHOWN = 0.1; // the drawn amplitude, of the drawing's size
const MODES_SHOWN = 6;

const isScalar = (value) => value === null || ["number", "string"].includes(typeof value);

// A table of records: a column per field that is a number or a word in every row, and per entry
// of a mapping that has the same names in every row (effective_mass: x, y).
export function recordsTable(caption, rows, units = {}) {
  const columns = [];
  for (const [key, value] of Object.entries(rows[0] || {})) {
    if (rows.every((row) => isScalar(row[key]))) columns.push([key, null]);
    else if (value && typeof value === "object" && !Array.isArray(value)) {
      const names = Object.keys(value);
      const same = rows.every((row) => row[key] && Object.keys(row[key]).join() === names.join() && Object.values(row[key]).every(isScalar));
      if (same) for (const name of names) columns.push([key, name]);
    }
  }
  const head = ([key, entry]) => {
    const unit = typeof units[key] === "string" ? ` [${units[key]}]` : "";
    return `${entry === null ? key : `${key} ${entry}`}${unit}`.replace(/_/g, " ");
  };
  return { caption, columns: columns.map(head), rows: rows.map((row) => columns.map(([key, entry]) => (entry === null ? row[key] : row[key][entry]))) };
}

function extent(lines) {
  const xs = [], ys = [];
  for (const points of Object.values(lines)) for (const [x, y] of points) { xs.push(x); ys.push(y); }
  return xs.length ? Math.max(Math.max(...xs) - Math.min(...xs), Math.max(...ys) - Math.min(...ys)) : 0;
}

function largest(shape) {
  let most = 0;
  for (const points of Object.values(shape.lines || {})) for (const [dx, dy] of points) most = Math.max(most, Math.hypot(dx, dy));
  return most;
}

// One period of each of the first modes: the centre lines and the bodies moved by a sin(phase).
export function modeFrames(report) {
  const rest = report.lines || {};
  const size = extent(rest);
  const toRadians = ((report.units || {}).angle || "rad").startsWith("deg") ? Math.PI / 180 : 1;
  const frames = [];
  for (const mode of (report.modes || []).slice(0, MODES_SHOWN)) {
    const shape = mode.shape || {};
    const most = largest(shape);
    if (!most || !size) continue;
    const scale = (SHOWN * size) / most;
    const heading = `mode ${mode.mode}: ${mode.frequency === null ? mode.kind : `${+mode.frequency.toPrecision(5)} Hz`}`;
    for (let i = 0; i < SWING_FRAMES; i += 1) {
      const a = scale * Math.sin((2 * Math.PI * i) / SWING_FRAMES);
      const elements = Object.fromEntries(Object.entries(rest).map(([name, points]) => [name, points.map((p, j) => {
        const d = (shape.lines[name] || [])[j] || [0, 0];
        return [p[0] + a * d[0], p[1] + a * d[1]];
      })]));
      const poses = Object.fromEntries(Object.entries(shape.bodies || {}).map(([body, [dx, dy, turn]]) => [body, [a * dx, a * dy, a * turn * toRadians]]));
      frames.push({ elements, poses, about: "reference", label: heading, mode: mode.mode });
    }
  }
  return frames;
}

export function modesTable(report) {
  const rows = (report.modes || []).map((mode) => ({
    mode: String(mode.mode), kind: mode.kind, frequency: mode.frequency, period: mode.period,
    effective_mass: mode.effective_mass,
    dominated_by: Object.keys(mode.energy_shares || {})[0] || "–",
  }));
  return recordsTable("Natural modes", rows, { frequency: "Hz", period: "s", effective_mass: (report.units || {}).effective_mass });
}

// A frequency response's series: the frequency (drawn on a log axis), per output its
// amplitude, in dB and its phase.
export function responseSeries(v, report) {
  const f = report.frequencies || [];
  v.series.frequency = f; v.units.frequency = (report.units || {}).frequency || "Hz";
  v.logScale = ["frequency"];
  let first = null;
  for (const [name, response] of Object.entries(report.responses || {})) {
    v.series[`${name} amplitude`] = response.amplitude; v.units[`${name} amplitude`] = response.unit;
    v.series[`${name} dB`] = response.amplitude.map((a) => (a ? 20 * Math.log10(a) : null)); v.units[`${name} dB`] = `dB re 1 ${response.unit}`;
    v.series[`${name} phase`] = response.phase; v.units[`${name} phase`] = "deg";
    first = first || name;
  }
  v.defaultCurve = first ? ["frequency", `${first} dB`] : null;
  const peaks = report.resonances || [];
  if (peaks.length) {
    const amplitudeUnits = new Set(peaks.map((peak) => ((report.responses || {})[peak.output] || {}).unit));
    const amplitude = amplitudeUnits.size === 1 ? [...amplitudeUnits][0] : "the output's unit";
    v.tables.push(recordsTable("Resonances", peaks, { frequency: "Hz", bandwidth: "Hz", phase: "deg", quality: "1", amplitude }));
  }
}

// A mode's row in the table animates that mode alone (click, or Enter when focused).
export function wireModeRows(panel, drawing, frames, playFrames) {
  for (const row of panel.querySelectorAll("tr[data-name]")) {
    const mode = Number(row.dataset.name);
    const own = frames.filter((frame) => frame.mode === mode);
    if (!own.length) continue;
    row.tabIndex = 0;
    row.title = `Animate mode ${mode}`;
    row.classList.add("pickable");
    const pick = () => playFrames(drawing, own);
    row.addEventListener("click", pick);
    row.addEventListener("keydown", (event) => { if (event.key === "Enter") pick(); });
  }
}

