// Field pickers. A form field that asks for numeric fields of the document by JSON pointer
// (forms.js finds them from the request schemas) gets a menu beside it of the open document's
// numeric fields: every number, number array entry and quantity string ("5 um") of its loads,
// prescribed motions, sections, materials, elements, bodies and contacts, each with a
// readable name ("actuation force y", "flexure h"). Clicking a load or an element in the
// drawing fills the path field focused last: a force's y component (its moment, a prescribed
// motion's first component), an element's section height. Typing the pointer stays possible.

import { formatNumber } from "./plot.js";

const $ = (id) => document.getElementById(id);
const QUANTITY = /^\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*[A-Za-z%][\w*/^.%-]*\s*$/;
const GROUPS = { loads: "Loads", motions: "Prescribed motions", sections: "Sections", materials: "Materials",
                 elements: "Elements", bodies: "Bodies", contacts: "Contacts" };
const TOPS = ["loads", "sections", "materials", "elements", "bodies", "contacts"];
const MOTION_ORDER = ["dy", "dx", "rotation"]; // a prescribed motion picked in the drawing: its first given
const CLICK_SLOP = 4; // px a pointer may move between press and click and still pick (more is a drag)

let known = null; // the open document, as the menus were last built from it
let last = null; // the path field focused last (its input)

const escaped = (part) => String(part).replace(/~/g, "~0").replace(/\//g, "~1");
const isNumeric = (v) => (typeof v === "number" && Number.isFinite(v)) || (typeof v === "string" && QUANTITY.test(v));

function walk(value, parts, words, out) {
  if (isNumeric(value)) out.push({ pointer: `/${parts.map(escaped).join("/")}`, label: words.join(" "), value });
  else if (Array.isArray(value)) value.forEach((item, k) => walk(item, [...parts, k], [...words, value.length === 2 ? "xy"[k] : String(k)], out));
  else if (value && typeof value === "object") for (const [key, item] of Object.entries(value)) walk(item, [...parts, key], [...words, key.replace(/_/g, " ")], out);
}

// The document's numeric fields, [{group, pointer, label, value}], loads first (document order within).
export function numericFields(doc) {
  const found = [];
  for (const top of TOPS) {
    for (const [name, entry] of Object.entries((doc && typeof doc[top] === "object" && doc[top]) || {})) {
      if (!entry || typeof entry !== "object") continue;
      const group = top === "loads" && entry.type === "displacement" ? "motions" : top;
      const here = [];
      walk(entry, [top, name], top === "contacts" ? [] : [name.replace(/_/g, " ")], here); // contacts: objects, sites, pairs
      found.push(...here.map((field) => ({ group, ...field })));
    }
  }
  return found.sort((a, b) => Object.keys(GROUPS).indexOf(a.group) - Object.keys(GROUPS).indexOf(b.group));
}

// The field a click on a load picks: a force's y, a moment, a prescribed motion's first component.
export function loadPointer(doc, name) {
  const load = doc && doc.loads && doc.loads[name];
  if (!load) return null;
  const base = `/loads/${escaped(name)}`;
  if (Array.isArray(load.force)) return `${base}/force/1`;
  if (isNumeric(load.moment)) return `${base}/moment`;
  const component = MOTION_ORDER.find((key) => isNumeric(load[key]));
  return component ? `${base}/${component}` : null;
}

// The field a click on an element picks: its section's height (else the section's first
// number), else its own height or first number.
export function elementPointer(doc, name) {
  const element = doc && doc.elements && doc.elements[name];
  if (!element) return null;
  const fields = numericFields(doc);
  const own = (prefix) => fields.filter((f) => f.pointer.startsWith(`${prefix}/`));
  const section = typeof element.section === "string" ? own(`/sections/${escaped(element.section)}`) : [];
  const choices = section.length ? section : own(`/elements/${escaped(name)}`);
  const height = choices.find((f) => /\/h$/.test(f.pointer));
  return (height || choices[0] || {}).pointer || null;
}

// A field's value as the menu shows it: as the page writes numbers, a quantity's unit kept ("5 um").
const NUMBER = /^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?/;
const shown = (value) => String(value).trim().replace(NUMBER, (number) => formatNumber(Number(number)));

function fill(menu, doc) {
  const first = new Option("pick a field…", "");
  const groups = new Map();
  for (const field of numericFields(doc)) {
    if (!groups.has(field.group)) { const g = document.createElement("optgroup"); g.label = GROUPS[field.group]; groups.set(field.group, g); }
    const option = new Option(`${field.label} (${shown(field.value)})`, field.pointer);
    option.title = field.pointer;
    groups.get(field.group).append(option);
  }
  menu.replaceChildren(first, ...groups.values());
  menu.value = "";
}

function fillList(list, doc) {
  list.replaceChildren(...numericFields(doc).map((field) => { const o = new Option(field.label, field.pointer); o.label = field.label; return o; }));
}

// The pointer into a path field: it replaces a single path, joins a list of paths (once).
export function put(input, pointer) {
  if (input.dataset.pointer === "many") {
    const paths = input.value.split(",").map((s) => s.trim()).filter(Boolean);
    if (!paths.includes(pointer)) paths.push(pointer);
    input.value = paths.join(", ");
  } else {
    input.value = pointer;
  }
  input.removeAttribute("aria-invalid");
  input.dispatchEvent(new Event("input", { bubbles: true }));
  input.dispatchEvent(new Event("change", { bubbles: true }));
}

// The input of a path field with its menu beside it (`many`: a comma-separated list of paths).
export function withPicker(input, label, doc, many) {
  known = doc;
  input.dataset.pointer = many ? "many" : "one";
  const menu = document.createElement("select");
  menu.id = `${input.id}-pick`;
  menu.className = "picker";
  menu.dataset.for = input.id;
  menu.setAttribute("aria-label", `${label}: pick a field of the document`);
  menu.title = `${many ? "Add" : "Choose"} a field of the document, or click a load or an element in the drawing`;
  fill(menu, doc);
  menu.addEventListener("change", () => { if (menu.value) put(input, menu.value); menu.value = ""; last = input; });
  const row = document.createElement("div");
  row.className = "picked";
  row.append(input, menu);
  if (!many) {
    const list = document.createElement("datalist");
    list.id = `${input.id}-fields`;
    list.className = "picker-list";
    fillList(list, doc);
    input.setAttribute("list", list.id);
    row.append(list);
  }
  return row;
}

// The menus built again from the document as it is now (after an edit).
export function refreshPickers(doc) {
  known = doc;
  for (const menu of document.querySelectorAll("select.picker")) fill(menu, doc);
  for (const list of document.querySelectorAll("datalist.picker-list")) fillList(list, doc);
}

function pathFieldOf(element) {
  if (!element || !element.dataset) return null;
  if (element.dataset.pointer) return element;
  return element.dataset.for && element.classList.contains("picker") ? $(element.dataset.for) : null;
}

// Clicks in `drawing` on a load or an element fill the path field focused last; focus on any
// other control (not the drawing, nor the section around it) ends the picking.
export function wirePickers(drawing) {
  document.addEventListener("focusin", (event) => {
    if (drawing.contains(event.target) || event.target.contains(drawing)) return; // a click in the drawing focuses it or its section
    last = pathFieldOf(event.target);
    if (last) drawing.dataset.picking = "true"; else delete drawing.dataset.picking;
  });
  let down = null;
  drawing.addEventListener("pointerdown", (event) => { down = [event.clientX, event.clientY]; });
  drawing.addEventListener("click", (event) => {
    const moved = down && Math.hypot(event.clientX - down[0], event.clientY - down[1]) > CLICK_SLOP; // a pan, not a pick
    if (!last || !last.isConnected || moved || !(event.target instanceof Element)) return;
    const target = event.target.closest("[data-load], [data-element]");
    if (!target || !drawing.contains(target)) return;
    const pointer = target.dataset.load !== undefined ? loadPointer(known, target.dataset.load) : elementPointer(known, target.dataset.element);
    if (!pointer) return;
    put(last, pointer);
    last.focus();
  });
}
