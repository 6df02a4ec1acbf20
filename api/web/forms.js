// What the page can run: every analysis of /v1/solve (the service lists them) and every job
// kind, each with a form of its options. Defaults come from the open document (its sweep,
// contacts.path and simulate sections), so an example runs as its author meant.

const num = (value) => (value === "" || value === null || value === undefined ? undefined : Number(value));
const sweepOf = (doc) => doc.sweep || {};
const pathOf = (doc) => ((doc.contacts && doc.contacts.path && doc.contacts.path.parameters) || [])[0] || {};
const simulateOf = (doc) => doc.simulate || {};
const IMPACT_SCHEMES = ["event_driven", "moreau"];
const hasImpacts = (doc) => Boolean(doc.simulate && IMPACT_SCHEMES.includes(doc.simulate.scheme));

function sweepStop(doc) {
  const sweep = sweepOf(doc);
  if (sweep.stop !== undefined) return sweep.stop;
  return sweep.start ? -sweep.start : 1;
}

// Each field: [name, label, type, default(doc), help]. Types: text, number, checkbox, select:a|b, json.
const FORMS = {
  equilibrium: {
    fields: [
      ["target", "Solve for a target", "checkbox", (d) => Boolean(sweepOf(d).until), "the field's value at which the output reaches a value"],
      ["target_path", "Field", "text", (d) => sweepOf(d).path || "", "JSON pointer of a numeric field"],
      ["target_output", "Output", "text", (d) => (sweepOf(d).until || {}).output || ""],
      ["target_equals", "Equals", "number", (d) => (sweepOf(d).until || {}).equals ?? ""],
      ["stiffness", "Tangent stiffness", "checkbox", () => false],
    ],
    build: (v) => ({
      ...(v.target ? { target: { path: v.target_path, output: v.target_output, equals: num(v.target_equals) } } : {}),
      ...(v.stiffness ? { stiffness: true } : {}),
    }),
  },
  linearization: { fields: [["at", "At", "select:equilibrium|undeformed", () => "equilibrium"]], build: (v) => ({ at: v.at }) },
  inverse: {
    fields: [["displacements", "Displacements", "json", () => "{}", '{"body": [dx, dy, rotation]}']],
    build: (v) => ({ displacements: JSON.parse(v.displacements || "{}") }),
  },
  contact: {
    fields: [["penetrating_start", "Penetrating start", "select:approach|refuse", () => "approach"],
             ["thesis_recovery", "Thesis recovery", "checkbox", () => false]],
    build: (v) => ({ penetrating_start: v.penetrating_start, ...(v.thesis_recovery ? { thesis_recovery: true } : {}) }),
  },
  simulate: {
    fields: [
      ["until", "Until [s]", "number", (d) => simulateOf(d).until ?? ""],
      ["step", "Step [s]", "number", (d) => simulateOf(d).step ?? ""],
      ["scheme", "Scheme", "select:|newmark|generalized_alpha|event_driven|moreau", () => "", "empty: as in the document"],
      ["shapes", "Shapes for the animation", "checkbox", (d) => !hasImpacts(d)],
    ],
    build: (v) => ({ simulate: clean({ until: num(v.until), step: num(v.step), scheme: v.scheme || undefined,
                                       shapes: v.shapes || undefined }) }),
  },
  trace: {
    fields: [
      ["path", "Field", "text", (d) => sweepOf(d).path || ""],
      ["stop", "Stop", "number", (d) => sweepStop(d)],
      ["step", "First step", "number", (d) => (sweepOf(d).start !== undefined ? Math.abs(sweepStop(d) - sweepOf(d).start) / (sweepOf(d).steps || 100) : "")],
      ["max_points", "Most points", "number", () => 400],
    ],
    build: (v) => ({ trace: clean({ path: v.path, stop: num(v.stop), step: num(v.step), max_points: num(v.max_points) }) }),
  },
};

const JOBS = {
  sweep: {
    label: "sweep (job)", endpoint: "/v1/sweeps",
    fields: [
      ["path", "Field", "text", (d) => sweepOf(d).path || ""],
      ["start", "Start", "number", (d) => sweepOf(d).start ?? 0],
      ["stop", "Stop", "number", sweepStop],
      ["steps", "Steps", "number", (d) => sweepOf(d).steps ?? 20],
      ["continuation", "Load path (continuation)", "checkbox", () => true],
      ["outputs", "Outputs", "text", () => "", "comma-separated; empty: all"],
    ],
    build: (v) => ({
      parameters: [{ path: v.path, start: num(v.start), stop: num(v.stop), steps: num(v.steps) }],
      ...(v.continuation ? { continuation: v.path } : {}),
      ...(v.outputs.trim() ? { outputs: v.outputs.split(",").map((s) => s.trim()).filter(Boolean) } : {}),
    }),
  },
  contact_path: {
    label: "contact path (job)", endpoint: "/v1/contacts",
    fields: [
      ["path", "Field", "text", (d) => pathOf(d).path || ""],
      ["start", "Start", "number", (d) => pathOf(d).start ?? ""],
      ["stop", "Stop", "number", (d) => pathOf(d).stop ?? ""],
      ["steps", "Steps", "number", (d) => pathOf(d).steps ?? 20],
    ],
    build: (v) => ({ path: [{ path: v.path, start: num(v.start), stop: num(v.stop), steps: num(v.steps) }] }),
  },
  simulation: {
    label: "simulation (job)", endpoint: "/v1/simulations",
    fields: [["until", "Until [s]", "number", (d) => simulateOf(d).until ?? ""],
             ["step", "Step [s]", "number", (d) => simulateOf(d).step ?? ""],
             ["shapes", "Shapes for the animation", "checkbox", (d) => !hasImpacts(d)]],
    build: (v) => ({ simulate: clean({ until: num(v.until), step: num(v.step), shapes: v.shapes || undefined }) }),
  },
  optimize: {
    label: "optimize (job)", endpoint: "/v1/optimize",
    fields: [["starts", "Starts", "number", (d) => (d.optimize || {}).starts ?? ""]],
    build: (v, d) => (num(v.starts) && d.optimize ? { problem: { ...d.optimize, starts: num(v.starts) } } : {}),
  },
  impact_study: {
    label: "impact study (job)", endpoint: "/v1/impact-studies",
    fields: [["fields", "Fields", "json", () => "[]", '[{"path": "/contacts/sites/pin/radius", "step": 0.001}]'],
             ["tolerance", "Tolerance", "number", () => 0.05]],
    build: (v) => ({ study: { fields: JSON.parse(v.fields || "[]"), tolerance: num(v.tolerance) } }),
  },
};

function clean(object) {
  return Object.fromEntries(Object.entries(object).filter(([, value]) => value !== undefined && value !== ""));
}

// The choices of the Run menu: solve analyses (as the service lists them), then the jobs.
export function choices(analyses) {
  return [...analyses.map((name) => ({ id: `solve:${name}`, label: name, kind: "solve", analysis: name })),
          ...Object.entries(JOBS).map(([id, job]) => ({ id: `job:${id}`, label: job.label, kind: "job", job: id, endpoint: job.endpoint }))];
}

function formOf(choice) {
  return choice.kind === "solve" ? FORMS[choice.analysis] || { fields: [], build: () => ({}) } : JOBS[choice.job];
}

function inputFor([name, label, type, initial, help], doc) {
  const wrapper = document.createElement("div");
  wrapper.className = "field";
  const id = `option-${name}`;
  const caption = document.createElement("label");
  caption.htmlFor = id;
  caption.textContent = label;
  let input;
  if (type.startsWith("select:")) {
    input = document.createElement("select");
    for (const option of type.slice(7).split("|")) input.append(new Option(option || "(document)", option));
  } else {
    input = document.createElement("input");
    input.type = type === "json" ? "text" : type;
    if (type === "number") input.step = "any";
  }
  input.id = id;
  input.name = name;
  const value = initial(doc);
  if (type === "checkbox") input.checked = Boolean(value);
  else input.value = value;
  if (help) { input.title = help; input.placeholder = help; }
  wrapper.append(caption, input);
  return wrapper;
}

export function renderForm(fieldset, choice, doc) {
  const legend = fieldset.querySelector("legend");
  fieldset.replaceChildren(legend);
  const form = formOf(choice);
  for (const field of form.fields) fieldset.append(inputFor(field, doc || {}));
  if (!form.fields.length) {
    const none = document.createElement("p");
    none.className = "hint";
    none.textContent = "No options: the document says it all (more fields below).";
    fieldset.append(none);
  }
}

function values(fieldset) {
  const out = {};
  for (const input of fieldset.querySelectorAll("input, select")) out[input.name] = input.type === "checkbox" ? input.checked : input.value;
  return out;
}

// The request body of the choice: the document, the model, the form's fields, then `extra`
// (an object of further request fields) over them.
export function buildRequest(choice, fieldset, doc, model, extra) {
  const request = { document: doc, ...(model ? { model } : {}), ...formOf(choice).build(values(fieldset), doc || {}) };
  if (choice.kind === "solve") request.analysis = choice.analysis;
  for (const [key, value] of Object.entries(extra || {})) {
    const both = value && typeof value === "object" && !Array.isArray(value) && request[key] && typeof request[key] === "object";
    request[key] = both ? { ...request[key], ...value } : value;
  }
  return JSON.parse(JSON.stringify(request)); // drops fields left undefined
}
