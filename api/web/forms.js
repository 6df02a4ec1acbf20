// What the page can run, and the form of each, made from the service's own schemas: every
// analysis of /v1/solve (GET /v1/analyses: its options' JSON schema) and every job kind (each
// POST of /openapi.json answered 202, with its request's schema). A field's description is
// its hint; its starting value is the open document's field at its `document_default` (a JSON
// pointer), else its `form_default`, else its schema default, so an example runs as its
// author meant. An input's id is "option-" and the field's JSON pointer in the request with
// "-" between its parts: the pointer of a 422 finds its input. A field asking for numeric
// fields of the document by JSON pointer has a menu of them beside it (pickers.js).

import { ApiProblem } from "./api.js";
import { withPicker } from "./pickers.js";

// The fields every request has, set elsewhere on the page (the editor, the model menu, Extra).
const COMMON = new Set(["document", "example", "model", "overrides", "options", "analysis"]);

function lookup(root, ref) {
  return ref.replace(/^#\//, "").split("/").reduce((node, part) => (node ? node[part] : undefined), root);
}

function resolved(schema, root) {
  return schema && schema.$ref ? resolved(lookup(root, schema.$ref), root) : schema || {};
}

// (the schema without its null alternative, whether null was one)
function withoutNull(schema, root) {
  const options = schema.anyOf || schema.oneOf;
  if (!options) return [resolved(schema, root), false];
  const rest = options.filter((s) => s.type !== "null");
  return [rest.length === 1 ? resolved(rest[0], root) : { anyOf: rest }, rest.length < options.length];
}

const isObjectModel = (s) => s.type === "object" && s.properties;

// The field tree of a schema's properties: {key, path, label, kind, schema, optional, children}.
function fieldsOf(schema, root, path = [], skip = COMMON) {
  const deprecated = ([, raw]) => /^deprecated\b/.test(raw.description || ""); // kept by the API for old clients, never offered
  return Object.entries(schema.properties || {}).filter(([key]) => !skip.has(key)).filter((entry) => !deprecated(entry)).map(([key, raw]) => {
    const [s, nullable] = withoutNull(raw, root);
    const label = raw.title || key.charAt(0).toUpperCase() + key.slice(1).replace(/_/g, " ");
    const field = { key, path: [...path, key], label, schema: { ...s, ...raw },
                    optional: nullable || !(schema.required || []).includes(key) };
    if (isObjectModel(s)) return { ...field, kind: "group", children: fieldsOf(s, root, field.path, new Set()) };
    const item = s.type === "array" ? resolved(s.items, root) : null;
    if (item && isObjectModel(item)) {
      return { ...field, kind: "list", children: fieldsOf(item, root, [...field.path, "0"], new Set()) };
    }
    if (s.type === "boolean") return { ...field, kind: "checkbox" };
    if (s.enum || s.const !== undefined) return { ...field, kind: "select", choices: s.enum || [s.const] };
    if (s.type === "number" || s.type === "integer") return { ...field, kind: "number" };
    if (s.type === "string") return { ...field, kind: "text" };
    if (s.type === "array" && resolved(s.items, root).type === "string") return { ...field, kind: "names" };
    return { ...field, kind: "json" };
  });
}

function pointed(doc, pointer) {
  if (!doc || !pointer) return undefined;
  return pointer.split("/").slice(1).reduce((node, part) => (node && typeof node === "object" ? node[part] : undefined), doc);
}

// A field starts from the request a job was asked (`asked`, on its page) where that gives it,
// else from the document at its own document_default, else at its key under its group's (`base`).
function startOf(field, doc, base, asked = null) {
  const given = pointed(asked, `/${field.path.join("/")}`);
  if (given !== undefined) return given;
  const fromDoc = pointed(doc, field.schema.document_default ?? (base ? `${base}/${field.key}` : undefined));
  if (fromDoc !== undefined) return fromDoc;
  if (field.schema.form_default !== undefined) return field.schema.form_default;
  return field.schema.default ?? undefined;
}

// The choices of the Run menu: the analyses (as the service lists them), then the job kinds.
export function choices(analyses, openapi) {
  const solve = analyses.map((a) => ({ id: `solve:${a.name}`, label: a.name, kind: "solve", analysis: a.name,
                                       summary: a.summary, fields: fieldsOf(a.options, a.options) }));
  const jobs = [];
  for (const [path, operations] of Object.entries((openapi && openapi.paths) || {})) {
    const post = operations.post;
    if (!post || !post.responses || !post.responses["202"]) continue;
    const body = resolved(post.requestBody.content["application/json"].schema, openapi);
    if (!body.properties) continue; // a union: the analysis job takes /v1/solve's body, whose analyses the menu has
    const id = (post.operationId || path.split("/").pop()).replace(/^create_/, "");
    jobs.push({ id: `job:${id}`, label: `${id.replace(/_/g, " ")} (job)`, kind: "job", job: id, endpoint: path,
                summary: post.summary || "", fields: fieldsOf(body, openapi) });
  }
  return [...solve, ...jobs];
}

const inputId = (path) => `option-${path.join("-")}`;

// A field that asks for numeric fields of the document by JSON pointer (one, or a list): its
// description says so, or its schema's example is a pointer. It gets a picker (pickers.js).
function asksForPointer(field) {
  if (field.kind !== "text" && field.kind !== "names") return false;
  const example = (field.schema.examples || [])[0];
  const first = Array.isArray(example) ? example[0] : example;
  return /JSON pointer|field pointer/i.test(field.schema.description || "") || (typeof first === "string" && first.startsWith("/"));
}

function hinted(element, field) {
  const help = field.schema.description || "";
  if (help) element.title = help;
  return element;
}

function leafInput(field, doc, base, asked) {
  const wrapper = document.createElement("div");
  wrapper.className = "field";
  const caption = document.createElement("label");
  caption.htmlFor = inputId(field.path);
  caption.textContent = field.schema.unit ? `${field.label} [${field.schema.unit}]` : field.label;
  let input;
  const start = startOf(field, doc, base, asked);
  if (field.kind === "select") {
    input = document.createElement("select");
    if (field.optional) input.append(new Option("(default)", ""));
    for (const choice of field.choices) input.append(new Option(choice, choice));
    input.value = start ?? "";
  } else {
    input = document.createElement("input");
    input.type = field.kind === "checkbox" || field.kind === "number" ? field.kind : "text";
    if (field.kind === "number") input.step = "any";
    if (field.kind === "checkbox") input.checked = Boolean(start);
    else if (field.kind === "json") input.value = start === undefined ? "" : JSON.stringify(start);
    else if (field.kind === "names") input.value = Array.isArray(start) ? start.join(", ") : "";
    else input.value = start ?? "";
    if (field.kind === "names") input.placeholder = "comma-separated";
    else if (field.schema.description && field.kind !== "checkbox") input.placeholder = field.schema.description;
  }
  input.id = inputId(field.path);
  input.dataset.kind = field.kind;
  const control = hinted(input, field);
  wrapper.append(caption, asksForPointer(field) ? withPicker(control, field.label, doc, field.kind === "names") : control);
  return wrapper;
}

function groupInput(field, doc, base, asked) {
  const own = field.schema.document_default ?? (base ? `${base}/${field.key}` : undefined);
  const group = document.createElement("fieldset");
  group.className = "group";
  const legend = document.createElement("legend");
  if (field.optional) {
    const enabled = document.createElement("input");
    enabled.type = "checkbox";
    enabled.id = inputId(field.path);
    enabled.dataset.kind = "enable";
    const given = pointed(asked, `/${field.path.join("/")}`);
    enabled.checked = asked ? given !== undefined && given !== null : pointed(doc, own) !== undefined || field.schema.form_default === true;
    const caption = document.createElement("label");
    caption.htmlFor = enabled.id;
    caption.textContent = field.label;
    legend.append(hinted(enabled, field), caption);
  } else {
    legend.textContent = field.label;
  }
  group.append(legend);
  for (const child of field.children) group.append(inputFor(child, doc, own, asked));
  return group;
}

function inputFor(field, doc, base, asked) {
  return field.kind === "group" || field.kind === "list" ? groupInput(field, doc, base, asked) : leafInput(field, doc, base, asked);
}

// The choice's form; `asked` (a job's request, on its page): each field as it was asked.
export function renderForm(fieldset, choice, doc, asked = null) {
  const legend = fieldset.querySelector("legend");
  fieldset.replaceChildren(legend);
  for (const field of choice.fields) fieldset.append(inputFor(field, doc || {}, undefined, asked));
  if (!choice.fields.length) {
    const none = document.createElement("p");
    none.className = "hint";
    none.textContent = "No options: the document says it all (more fields below).";
    fieldset.append(none);
  }
}

function formProblem(path, message) {
  const pointer = `/${path.join("/")}`;
  return new ApiProblem(422, `${pointer}: ${message}`, pointer);
}

const same = (a, b) => JSON.stringify(a) === JSON.stringify(b);

// The value of a field as the form holds it; undefined: not given (the service's default).
function valueOf(field, fieldset) {
  const input = fieldset.querySelector(`#${CSS.escape(inputId(field.path))}`);
  if (field.kind === "group" || field.kind === "list") {
    if (field.optional && input && !input.checked) return undefined;
    const object = {};
    for (const child of field.children) {
      const value = valueOf(child, fieldset);
      if (value !== undefined) object[child.key] = value;
    }
    if (field.optional && !Object.keys(object).length) return undefined;
    return field.kind === "list" ? [object] : object;
  }
  if (!input) return undefined;
  if (field.kind === "checkbox") return same(input.checked, field.schema.default ?? false) ? undefined : input.checked;
  const text = input.value.trim();
  if (text === "") return undefined;
  if (field.kind === "number") return Number(text);
  if (field.kind === "names") return text.split(",").map((s) => s.trim()).filter(Boolean);
  if (field.kind === "json") {
    try { return JSON.parse(text); } catch (error) { throw formProblem(field.path, `not JSON (${error.message})`); }
  }
  return field.kind === "select" && same(text, field.schema.default) && !field.optional ? undefined : text;
}

function merged(into, extra) {
  for (const [key, value] of Object.entries(extra || {})) {
    const both = value && typeof value === "object" && !Array.isArray(value) && into[key] && typeof into[key] === "object";
    into[key] = both ? { ...into[key], ...value } : value;
  }
  return into;
}

// The request body of the choice: the document, the model, the form's fields, then `extra`
// (an object of further request fields) over them.
export function buildRequest(choice, fieldset, doc, model, extra) {
  const request = { document: doc, ...(model ? { model } : {}) };
  if (choice.kind === "solve") request.analysis = choice.analysis;
  for (const field of choice.fields) {
    const value = valueOf(field, fieldset);
    if (value !== undefined) request[field.key] = value;
  }
  return JSON.parse(JSON.stringify(merged(request, extra))); // drops fields left undefined
}
