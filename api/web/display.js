// How the page shows a result's numbers: the rules of service/display.py (the command line's),
// so a quantity reads the same on a card, in a table and in a terminal. A quantity is shown in
// the document's unit while the largest shown lies in [0.1, 1e4) (not stresses and energies),
// else with the SI prefix on its first factor that puts the largest in [1, 1000) (0.00147 GPa ->
// 1.47 MPa, 1.2e-9 kg -> 1.2 ug); an energy in J (4.77 uN*mm -> 4.77 nJ); six significant
// digits; values below NOISE times the largest of their kind shown as 0 (round-off, not a
// result). tests/interfaces/test_display_js.py holds this module to the Python one, case by case.

export const SIGNIFICANT = 6;
export const NOISE = 1e-9;
const KEPT = [0.1, 1e4];
const ALWAYS_PREFIXED = ["Pa", "J"];
const PREFIXES = { p: 1e-12, n: 1e-9, u: 1e-6, m: 1e-3, "": 1, k: 1e3, M: 1e6, G: 1e9 };
const PREFIXED = ["m", "g", "N", "Pa", "J", "Hz", "s", "W"];
// SI value of one base unit (g in kg, as kg is SI's)
const BASES = { m: 1, g: 1e-3, N: 1, Pa: 1, J: 1, Hz: 1, s: 1, W: 1 };

// `digits` significant digits (SIGNIFICANT), trailing zeros dropped, -0 as 0: Python's
// f"{value:.6g}" (the exponent form below 1e-4 and from 10^digits on).
export function numberText(value, digits = SIGNIFICANT) {
  if (typeof value !== "number" || Number.isNaN(value)) return "–";
  if (!Number.isFinite(value)) return value > 0 ? "∞" : "−∞";
  if (value === 0) return "0";
  const [mantissa, power] = value.toExponential(digits - 1).split("e");
  const exponent = Number(power);
  if (exponent < -4 || exponent >= digits) {
    return `${trimmed(mantissa)}e${exponent < 0 ? "-" : "+"}${String(Math.abs(exponent)).padStart(2, "0")}`;
  }
  return trimmed(value.toFixed(Math.max(0, digits - 1 - exponent)));
}

const trimmed = (text) => (text.includes(".") ? text.replace(/\.?0+$/, "") : text);

// [prefix, base, rest] of a unit whose first factor takes an SI prefix, else null.
function split(unit) {
  const found = /^([A-Za-zµ]+)(.*)$/.exec(unit.trim());
  if (!found) return null;
  const first = found[1].replace("µ", "u");
  const rest = found[2];
  if (PREFIXED.includes(first)) return ["", first, rest];
  if (first.length > 1 && first[0] in PREFIXES && PREFIXED.includes(first.slice(1))) return [first[0], first.slice(1), rest];
  return null;
}

// The SI value of one `unit` built of prefixed base units joined by * and / (null if another).
function siValue(unit) {
  let value = 1;
  for (const [k, token] of unit.split(/([*/])/).entries()) {
    if (k % 2) continue;
    const parts = split(token);
    if (!parts || parts[2]) return null;
    const factor = PREFIXES[parts[0]] * BASES[parts[1]];
    value = k > 0 && unit.split(/([*/])/)[k - 1] === "/" ? value / factor : value * factor;
  }
  return value;
}

// How one quantity is shown: {unit, factor, floor, text(value, withUnit)}.
export function display(unit, values, kind = null) {
  const finite = values.filter((v) => typeof v === "number" && Number.isFinite(v)).map(Math.abs);
  const floor = NOISE * Math.max(0, ...finite);
  const largest = Math.max(0, ...finite.filter((v) => v >= floor));
  const make = (shownUnit, factor) => ({
    unit: shownUnit, factor, floor,
    value: (v) => (typeof v !== "number" || !Number.isFinite(v) ? null : Math.abs(v) < floor ? 0 : v * factor),
    text(v, withUnit = false) {
      const shown = this.value(v);
      const text = shown === null ? "–" : numberText(shown);
      return withUnit && shownUnit ? `${text} ${shownUnit}` : text;
    },
  });
  if (!unit || kind === "ratio") return make(unit || "", 1);
  let baseUnit = unit, toBase = 1;
  if (kind === "energy") {
    const si = siValue(unit);
    if (si === null) return make(unit, 1);
    baseUnit = "J"; toBase = si;
  }
  const parts = split(baseUnit);
  const always = parts !== null && ALWAYS_PREFIXED.includes(parts[1]);
  if (baseUnit === unit && largest >= KEPT[0] && largest < KEPT[1] && !always) return make(unit, 1);
  if (parts === null || largest === 0) return make(baseUnit, toBase);
  const [prefix, base, rest] = parts;
  const power = Number((/^\^(-?\d+)/.exec(rest) || [null, 1])[1]); // mm^2: a prefix counts twice
  let best = null;
  for (const [candidate, scale] of Object.entries(PREFIXES)) {
    const factor = toBase * (PREFIXES[prefix] / scale) ** power;
    const shown = largest * factor;
    const score = shown >= 1 && shown < 1000 ? 0 : Math.min(Math.abs(Math.log10(shown)), Math.abs(Math.log10(shown / 1000)));
    if (best === null || score < best[0]) best = [score, `${candidate}${base}${rest}`, factor];
  }
  return make(best[1], best[1] === unit ? 1 : best[2]);
}

const HEAD_UNIT = /^(.*?)\s*([[(])([^[\]()]*)[\])]$/;
const NOT_RESULTS = ["residual", "tolerance"];

// A table's numbers as shown: each numeric column in the display of the unit its head ends
// with ("x [mm]", "mass (kg)"), the head then naming the display unit; a table with a "unit"
// column in one display per row (its numbers share that row's unit); residual and tolerance
// columns exactly (four digits). Returns {columns, rows} whose numbers are now text, and
// `numeric`, per row per cell, whether it was a number (its exact value stays in `exact`).
export function shownTable({ columns, rows }) {
  const isNumber = (value) => typeof value === "number";
  const unitColumn = columns.indexOf("unit");
  const shownRows = rows.map((row) => row.slice());
  const heads = columns.slice();
  if (unitColumn >= 0) {
    rows.forEach((row, r) => {
      const values = row.filter((value, c) => c !== unitColumn && isNumber(value));
      const shown = display(String(row[unitColumn] || ""), values, null);
      row.forEach((value, c) => { if (c !== unitColumn && isNumber(value)) shownRows[r][c] = shown.text(value); });
      if (values.length && row[unitColumn]) shownRows[r][unitColumn] = shown.unit;
    });
  } else {
    columns.forEach((head, c) => {
      const values = rows.map((row) => row[c]).filter(isNumber);
      if (!values.length || typeof head !== "string") return;
      const found = HEAD_UNIT.exec(head);
      const unit = found ? found[3].trim() : "";
      const exact = NOT_RESULTS.some((word) => head.toLowerCase().includes(word));
      const kind = /energy/i.test(head) && !/share|relative/i.test(head) ? "energy" : null;
      const shown = display(unit, values, kind);
      rows.forEach((row, r) => { if (isNumber(row[c])) shownRows[r][c] = exact ? exactText(row[c]) : shown.text(row[c]); });
      if (found && !exact && shown.unit !== unit) heads[c] = `${found[1]} ${found[2]}${shown.unit}${found[2] === "[" ? "]" : ")"}`;
    });
  }
  return { columns: heads, rows: shownRows, numeric: rows.map((row) => row.map(isNumber)) };
}

// A residual or a tolerance: its own value, four digits (service.display.exact).
export const exactText = (value) => numberText(value, 4);
