// Completion of field names in the editor, from the JSON schema of the mechanism document
// (the service's /workbench/document-schema.json): the fields the object at the cursor may
// have and does not have yet, its kind chosen by its "type" where the schema has kinds.

import { syntaxTree } from "./vendor/codemirror.js";

let schema = null;

function loadSchema() {
  schema ??= fetch("/workbench/document-schema.json").then((r) => (r.ok ? r.json() : null)).catch(() => null);
  return schema;
}

// --- the schema: the object schemas a place may hold ----------------------------------------
function resolved(root, node) {
  let at = node;
  for (let hops = 0; at && at.$ref && hops < 20; hops++) {
    at = at.$ref.split("/").slice(1).reduce((value, key) => value && value[key], root);
  }
  return at || {};
}

// The object schemas `node` may be (through references and unions), each once.
function objectsOf(root, node, kind) {
  const found = [];
  const stack = [node];
  while (stack.length) {
    const at = resolved(root, stack.pop());
    const members = [...(at.anyOf || []), ...(at.oneOf || []), ...(at.allOf || [])];
    if (members.length) { stack.push(...members.reverse()); continue; }
    if (at.properties || at.additionalProperties) found.push(at);
  }
  const chosen = kind ? found.filter((o) => !o.properties?.type || kindsOf(root, o.properties.type).includes(kind)) : found;
  return chosen.length ? chosen : found;
}

function kindsOf(root, node) {
  const at = resolved(root, node);
  return at.const !== undefined ? [at.const] : at.enum || [];
}

// The schemas the field at `path` (keys, and null for an array's item) may be.
function schemasAt(root, path) {
  let places = [root];
  for (const key of path) {
    const next = [];
    for (const place of places) {
      const at = resolved(root, place);
      if (key === null) { next.push(...[at.items, ...(at.prefixItems || [])].filter(Boolean)); continue; }
      for (const object of objectsOf(root, at)) {
        const field = object.properties?.[key] ?? (typeof object.additionalProperties === "object" ? object.additionalProperties : null);
        if (field) next.push(field);
      }
    }
    places = next;
  }
  return places;
}

function fieldsAt(root, path, kind) {
  const fields = new Map();
  for (const place of schemasAt(root, path)) {
    for (const object of objectsOf(root, place, kind)) {
      for (const [name, field] of Object.entries(object.properties || {})) if (!fields.has(name)) fields.set(name, resolved(root, field));
    }
  }
  return fields;
}

// Every field name of the schema: offered where the place is not known.
function everyField(root) {
  const fields = new Map();
  for (const object of [root, ...Object.values(root.$defs || {})]) {
    for (const [name, field] of Object.entries(object.properties || {})) if (!fields.has(name)) fields.set(name, resolved(root, field));
  }
  return fields;
}

// --- the text: the path of the object at the cursor, its keys and its kind --------------------
const unquoted = (state, node) => { try { return JSON.parse(state.sliceDoc(node.from, node.to)); } catch { return null; } };

function jsonPlace(context) {
  let node = syntaxTree(context.state).resolveInner(context.pos, -1);
  const from = context.matchBefore(/[\w$-]*/).from;
  if (node.name === "PropertyName") node = node.parent.parent;
  else if (node.name === "⚠" || node.name === "String") node = node.parent;
  if (!node || node.name !== "Object") return null;
  const keys = node.getChildren("Property").map((p) => p.firstChild && unquoted(context.state, p.firstChild));
  const typed = node.getChildren("Property").find((p) => p.firstChild && unquoted(context.state, p.firstChild) === "type");
  const kind = typed && typed.lastChild && typed.lastChild.name === "String" ? unquoted(context.state, typed.lastChild) : null;
  const path = [];
  for (let at = node; at.parent; at = at.parent) {
    if (at.parent.name === "Property" && at.parent.firstChild) path.unshift(unquoted(context.state, at.parent.firstChild));
    else if (at.parent.name === "Array") path.unshift(null);
  }
  // the quotes typed around the name (closeBrackets adds the closing one) are replaced too
  const before = context.state.sliceDoc(from - 1, from) === '"' ? 1 : 0;
  const after = before && context.state.sliceDoc(context.pos, context.pos + 1) === '"' ? 1 : 0;
  const apply = (name) => (view, _completion, start, end) => {
    const insert = `"${name}": `;
    view.dispatch({ changes: { from: start - before, to: end + after, insert }, selection: { anchor: start - before + insert.length },
                    userEvent: "input.complete" });
  };
  return { from, keys, kind, path, apply };
}

// A YAML line: its indent, whether it is a sequence item ("- "), its key and the value after it.
function yamlLine(text) {
  const at = text.search(/\S/);
  if (at < 0 || text[at] === "#") return null;
  const entry = /^(- )?(?:["']?([\w$-]+)["']?:(?:\s+(.*))?\s*$)?/.exec(text.slice(at));
  const item = Boolean(entry[1]);
  return { at, item, key: entry[2], value: (entry[3] || "").replace(/["']/g, "").trim(), column: item ? at + 2 : at };
}

// The fields of the object whose keys sit at `column`, on the lines after line `number`.
function fieldsBelow(doc, number, column) {
  const fields = [];
  for (let n = number + 1; n <= doc.lines; n++) {
    const line = yamlLine(doc.line(n).text);
    if (!line || line.column > column) continue;
    if (line.column < column || (line.item && line.column === column)) break;
    if (line.key) fields.push(line);
  }
  return fields;
}

function yamlPlace(context) {
  const { doc } = context.state;
  const here = doc.lineAt(context.pos);
  const typing = /^(\s*)(- )?([\w$-]*)$/.exec(here.text.slice(0, context.pos - here.from));
  if (!typing) return null;
  let column = typing[1].length + (typing[2] ? 2 : 0);
  let dash = typing[2] ? typing[1].length : -1; // once the object is known to be a sequence item: its dash's column
  const path = [], fields = fieldsBelow(doc, here.number, column);
  let first = true;
  for (let n = here.number - 1; n >= 1 && !(column === 0 && !first && dash < 0); n--) {
    const line = yamlLine(doc.line(n).text);
    if (!line) continue;
    if (dash >= 0) { // the key of the sequence the object is an item of
      if (line.at > dash || (line.at === dash && line.item)) continue;
      if (!line.key) return null;
      path.unshift(line.key, null);
    } else if (line.column === column) { // a key of the object
      if (first && line.key) fields.push(line);
      if (line.item) dash = line.at;
      continue;
    } else if (line.column > column) continue;
    else { // the key whose value the object is
      if (!line.key) return null;
      path.unshift(line.key);
    }
    first = false;
    column = line.column;
    dash = line.item ? line.at : -1;
  }
  const keys = fields.map((f) => f.key), kind = fields.find((f) => f.key === "type")?.value || null;
  return { from: context.pos - typing[3].length, keys, kind, path, apply: (name) => `${name}: ` };
}

// What a field holds, in the schema's words: "number | string", "object", ...
function typeOf(root, field) {
  const members = field.anyOf || field.oneOf || [field];
  const types = members.map((m) => resolved(root, m)).map((m) => m.type || (m.properties ? "object" : "")).filter((t) => t && t !== "null");
  return [...new Set(types)].join(" | ");
}

// The CodeMirror completion source: field names for the object at the cursor.
export async function fieldNames(context) {
  const json = context.state.sliceDoc(0, 1000).trimStart().startsWith("{");
  const place = json ? jsonPlace(context) : yamlPlace(context);
  if (!place || (!context.explicit && place.from === context.pos && !json)) return null;
  const root = await loadSchema();
  if (!root) return null;
  let fields = fieldsAt(root, place.path, place.kind);
  if (!fields.size) fields = everyField(root);
  const options = [...fields].filter(([name]) => !place.keys.includes(name)).map(([name, field]) => ({
    label: name, type: "property", apply: place.apply(name),
    detail: typeOf(root, field), info: field.description || undefined,
  }));
  return { from: place.from, options, validFor: /^[\w$-]*$/ };
}
