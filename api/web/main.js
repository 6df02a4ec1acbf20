// The workbench page: open an example or your own document, see it drawn to scale, run any
// analysis or job the service offers, and look at the result (tables, curves, energies,
// animation, downloads). On /jobs/{id} it follows that job.

import { ApiProblem, apiKey, documentPointer, get, post, setApiKey } from "./api.js";
import { clearFrames, playFrames, setFrames, wireAnimation } from "./animation.js";
import { edited, readDocument, setText, showProblems } from "./editor.js";
import { buildRequest, choices, renderForm } from "./forms.js";
import { jobView } from "./jobviews.js";
import { cancel, fullResult, follow, jobRequest, showProgress } from "./jobs.js";
import { csvOf, fillCurveChoices, renderCurve, renderEnergies, renderTables } from "./render.js";
import { resultView, withFieldLoads } from "./results.js";
import { fieldName } from "./names.js";
import { wireModeRows } from "./vibration.js";
import { drawScene } from "./scene.js";
import { resetView } from "./zoom.js";
import { offerArchive, wireDownloads, wireFabrication } from "./downloads.js";
import { clearCard, showCard, statusStyle } from "./card.js";
import { showRecentJobs } from "./recent.js";
import { defaultChoice, whyNot } from "./offers.js";
import { wireTabs } from "./tabs.js";
import { wireCompare } from "./compare.js";
import { refreshPickers, wirePickers } from "./pickers.js";
import { numberText } from "./display.js";

const $ = (id) => document.getElementById(id);
const DEFAULT_EXAMPLE = "gripper";
const REDRAW_AFTER_MS = 700;
const MAX_PATH_FRAMES = 200; // states of a sweep drawn for its animation
const PARTIAL_EVERY_MS = 1000;
// Analyses whose answer is one state of the document's mechanism: drawn deformed after them.
const DEFORMING = ["equilibrium", "linearization", "energy"];

const state = { loaded: false, finishedJob: null, overrides: {}, doc: null, drawing: null, view: null, result: null, name: "", choices: [], jobId: null, busy: false,
                example: "", opened: 0, csv: () => (state.view ? csvOf(state.view) : "") };

// A status line; `style` one of card.js' styles (running, ok, failed, cancelled) or "".
function say(id, text, style = "") {
  $(id).textContent = text;
  $(id).classList.toggle("failed", style === "failed");
  $(id).dataset.style = style;
}

// The Outputs tab's line while it has no result.
function hintResults(message) {
  const hint = document.createElement("p");
  hint.className = "hint";
  hint.textContent = message;
  $("panel-table").replaceChildren(hint);
}

// The results of the last run taken away: a new run or another document shows none until its own.
function clearResults(message = "Run an analysis to see its outputs.") {
  state.view = null; state.result = null;
  clearFrames();
  clearCard();
  hintResults(message);
  $("curve").replaceChildren();
  $("energy-plot").replaceChildren();
  $("raw").textContent = "";
  $("download-json").disabled = true;
  offerArchive(null);
  $("download-csv").disabled = true;
  $("tab-curves").disabled = true;
  $("tab-energies").disabled = true;
}

// The option of the form a request pointer names (its input's id is the pointer's parts,
// forms.js): marked invalid and focused; a pointer into a field of it finds the field.
function markOption(pointer) {
  for (const input of document.querySelectorAll("#options [aria-invalid]")) input.removeAttribute("aria-invalid");
  if (!pointer) return;
  const tokens = pointer.split("/").filter(Boolean);
  for (let n = tokens.length; n > 0; n -= 1) {
    const input = $(`option-${tokens.slice(0, n).join("-")}`);
    if (input) { input.setAttribute("aria-invalid", "true"); input.focus(); return; }
  }
}

// Run is refused while a run or a followed job goes on: aria-disabled, not `disabled`, so
// Enter on Run keeps the focus there.
function lockRun(locked) {
  state.busy = locked;
  if (locked) $("run").setAttribute("aria-disabled", "true");
  else $("run").removeAttribute("aria-disabled");
}

// A problem from the service or the page, shown at the field it names. A run the service
// refused (a 4xx answer: nothing ran) says so under Run, on the card and in the Outputs tab.
function report(error, where = "run-state") {
  const refused = error instanceof ApiProblem && error.status >= 400 && error.status < 500;
  const running = where === "run-state" && state.running;
  const message = String(error.message || error);
  if (running) {
    showCard(state.running.source, state.running.title, refused ? "refused" : "failed", null, message);
    if (!state.view) hintResults(refused ? "Not run: the service refused the request (why is under Run)." : "No result: the run failed (why is under Run).");
  }
  const prefix = running && refused ? "Refused: " : "";
  if (!(error instanceof ApiProblem)) { say(where, prefix + message, "failed"); return; }
  const inDocument = documentPointer(error.pointer);
  markOption(inDocument === null ? error.pointer : null);
  showProblems(error.problems.map((p) => ({ ...p, pointer: documentPointer(p.pointer) ?? p.pointer })));
  say(where, prefix + (inDocument !== null ? "the document has a problem (listed under it)." : error.message), "failed");
  if (inDocument !== null && state.drawing) $("drawing-caption").textContent = "The last drawing of a document that worked.";
}

async function draw(deformed = null) {
  const doc = await readDocument();
  state.doc = doc;
  refreshPickers(doc); // the path fields' menus list this document's fields
  const model = $("model").value || undefined;
  const body = { document: doc, model, ...(deformed ? { state: "equilibrium", overrides: deformed.overrides || {} } : {}) };
  state.drawing = await post("/v1/drawings", body);
  state.name = doc.name || "mechanism";
  $("mechanism-name").textContent = state.name;
  const frame = deformed && state.drawing.deformed ? { ...state.drawing.deformed, about: "reference" } : null;
  drawScene($("drawing"), state.drawing, frame);
  $("drawing-caption").textContent = frame ? `Deformed (solid) over undeformed (dashed); ${state.drawing.status}.` : "Undeformed, to scale.";
  showProblems([]);
  say("document-state", "");
  performance.mark("flexmech-drawn");
}

// The document drawn again; the Run menu offered anew for a new document (`fresh`) or after an
// edit that changes what it can be asked.
async function redraw(fresh = false) {
  try {
    clearFrames();
    await draw();
    const offers = JSON.stringify(state.drawing.offers || null);
    if (fresh || offers !== state.offers) { state.offers = offers; offerChoices(null, fresh); }
  } catch (error) { report(error, "document-state"); }
}

// On a narrow screen the results are below the form: the card is scrolled into view.
function revealCard() {
  const box = $("result-card").getBoundingClientRect();
  if (box.top > window.innerHeight || box.bottom < 0) $("result-card").scrollIntoView({ block: "start" });
}

function formatSeconds(seconds) {
  return seconds < 1 ? `${+(seconds * 1000).toPrecision(3)} ms` : `${+seconds.toPrecision(3)} s`;
}

// Another document: the last one's result, errors and job are not shown with it (a job
// followed is left to run on its page; a run's answer that comes later is not shown).
function newDocument() {
  clearResults();
  showProblems([]);
  say("run-state", "");
  say("document-state", "");
  $("job").hidden = true;
  state.jobId = null;
  state.opened += 1;
  state.overrides = {}; // the last document's run values are not this one's
  state.design = null;
  resetView($("drawing")); // the whole new mechanism, not the last one's zoom
}

async function openExample(name) {
  const doc = await get(`/v1/examples/${encodeURIComponent(name)}`);
  newDocument();
  setText(JSON.stringify(doc, null, 2));
  $("example-select").value = name;
  state.example = name;
  await redraw(true);
}

// Edits of the document exist only in the editor: another document replaces them only when
// the user says so (`what` names it).
function mayReplaceText(what) {
  return !edited() || window.confirm(`The document "${state.name}" has edits that are saved nowhere. Open ${what} and discard them?`);
}

function currentChoice() {
  return state.choices.find((c) => c.id === $("analysis").value) || state.choices[0];
}

// The Run menu: what the open document can be asked first; the rest greyed, each saying why
// not (the service's offers, drawn with the document). `wanted` is chosen if offered; a
// `fresh` document gets its own first analysis, an edited one keeps the chosen one if it can.
function offerChoices(wanted = null, fresh = false, asked = null) {
  const offers = state.drawing && state.drawing.offers;
  const open = state.choices.filter((c) => !whyNot(c, offers)), shut = state.choices.filter((c) => whyNot(c, offers));
  const kept = wanted || $("analysis").value;
  const items = open.map((c) => new Option(c.label, c.id));
  if (shut.length) {
    const group = document.createElement("optgroup");
    group.label = "Not for this document";
    for (const c of shut) {
      const reason = whyNot(c, offers);
      const option = new Option(`${c.label}: ${reason.split(": ")[0].slice(0, 80)}`, c.id);
      option.title = reason;
      option.disabled = true;
      group.append(option);
    }
    items.push(group);
  }
  $("analysis").replaceChildren(...items);
  $("analysis").value = (wanted || !fresh) && open.some((c) => c.id === kept) ? kept : (defaultChoice(open, state.doc) || open[0] || {}).id;
  renderForm($("options"), currentChoice(), state.doc, asked && currentChoice().id === wanted ? asked : null);
  document.body.dataset.offered = state.name; // the menu and the form are the document's (tests wait for it)
}

function showView(view, result) {
  view.run = { title: state.running ? state.running.title : "", model: $("model").value, document: state.name, at: Date.now() }; // its label when kept
  state.view = view; state.result = result;
  renderTables(view);
  fillCurveChoices(view);
  renderCurve(view);
  renderEnergies(view);
  $("raw").textContent = JSON.stringify(result, null, 2).slice(0, 200_000);
  $("download-json").disabled = false;
  $("download-csv").disabled = false;
  if (view.frames.length && state.drawing) {
    setFrames(state.drawing, view.frames, view.openAt ?? view.frames.length - 1);
    $("drawing-caption").textContent = view.frames.length === 1 ? "The state found, to scale over the undeformed mechanism (dashed)."
      : `${view.frames.length} states of the result, to scale over the undeformed mechanism (dashed): slide or play.`;
  }
}

async function runSolve(choice, request) {
  const opened = state.opened;
  const report = await post("/v1/solve", request);
  if (opened !== state.opened) return; // another document is open now: not its result
  showView(resultView("solve", report, state.drawing), report);
  if (report.analysis === "modes" && state.drawing) wireModeRows($("panel-table"), state.drawing, state.view.frames, playFrames);
  const took = report.seconds ? `in ${formatSeconds(report.seconds)}` : "";
  showCard(`solve:${choice.analysis}`, choice.analysis, report.status, report, took);
  say("run-state", `${choice.analysis}: ${report.status}${took ? ` ${took}` : ""}`, statusStyle(report.status));
  if (DEFORMING.includes(choice.analysis)) {
    const overrides = { ...(request.overrides || {}) };
    if (report.target && report.target.value !== null) overrides[report.target.path] = report.target.value;
    await draw({ overrides });
  }
}

// A one-field sweep's states, drawn by the service along the field's values (evenly chosen).
async function sweepFrames(result) {
  const [field] = result.parameters || [];
  if (!state.doc || !field || result.parameters.length !== 1 || !result.points.length) return;
  const values = result.points.map((p) => p.values[0]);
  const every = Math.ceil(values.length / MAX_PATH_FRAMES);
  const chosen = values.filter((_, i) => i % every === 0 || i === values.length - 1);
  const answer = await post("/v1/drawings", { document: state.doc, model: $("model").value || undefined, overrides: state.overrides,
                                              state: "path", path: { path: field.path, values: chosen } });
  const states = answer.frames.map((f) => ({ elements: f.elements, poses: f.poses, about: "reference",
                                             label: `${fieldName(field.path)} = ${numberText(+f.value)} ${answer.unit}${f.status === "converged" ? "" : ` (${f.status})`}` }));
  const frames = withFieldLoads(states, answer, field.path, answer.frames.map((f) => f.value)); // a swept load at each state's value
  state.drawing = answer;
  setFrames(answer, frames);
  $("drawing-caption").textContent = `${frames.length} states of the sweep, each solved from the one before, over the undeformed mechanism (dashed).`;
}

async function showJobResult(id, status) {
  state.finishedJob = id; // a partial read still under way is not shown after this
  const answer = await fullResult(id);
  const view = jobView(status.kind, answer.result, state.drawing);
  showView(view, answer.result);
  state.design = view.design || null; // the fabrication drawings draw the optimum shown
  if (view.design && state.doc) await draw({ overrides: view.design }); // the optimum, deformed
  if (status.kind === "sweep") await sweepFrames(answer.result);
  showCard(`job:${status.kind}`, `${status.kind.replace(/_/g, " ")} job`, status.status, answer.result, status.error || "");
  offerArchive(status.status === "succeeded" && status.links ? status.links.archive : null, (message) => say("run-state", message, "error"));
  showRecentJobs();
  say("run-state", `job ${status.status}${status.error ? `: ${status.error}` : ""}`, statusStyle(status.status));
}

// While a job runs, its points so far (tables and curves), read again at most every
// PARTIAL_EVERY_MS when more are done.
function partialResults(id) {
  let shownDone = 0, last = 0, reading = false;
  return async (status) => {
    const now = performance.now();
    if (reading || status.status !== "running" || status.progress.done <= shownDone || now - last < PARTIAL_EVERY_MS) return;
    reading = true; last = now;
    try {
      const answer = await fullResult(id);
      if (state.jobId !== id || state.finishedJob === id || answer.status !== "running") return;
      shownDone = status.progress.done;
      const view = jobView(status.kind, answer.result, state.drawing);
      showView({ ...view, frames: [] }, answer.result); // the animation comes with the whole result
      showCard(`job:${status.kind}`, `${status.kind.replace(/_/g, " ")} job`, "running", answer.result); // its progress: under Run, one figure
      if (view.frames.length && state.drawing) {  // the latest state drawn while it runs (the slider goes back)
        setFrames(state.drawing, view.frames);
        $("drawing-caption").textContent = `Running: the latest of ${view.frames.length} states so far, over the undeformed mechanism (dashed).`;
      }
    } catch { /* the final result follows; a missed partial read changes nothing */ } finally { reading = false; }
  };
}

// The job's page in the address bar (reload or a bookmark comes back to it).
function showJobPage(id) {
  if (location.pathname !== `/jobs/${id}`) history.pushState({ job: id }, "", `/jobs/${id}`);
  showRecentJobs();
}

async function runJob(choice, request) {
  const status = await post(choice.endpoint, request);
  state.jobId = status.id;
  state.running.source = `job:${status.kind}`;
  showJobPage(status.id);
  showProgress(status);
  say("run-state", `${choice.label} running`, "running");
  const last = await follow(status.id, partialResults(status.id), () => state.jobId === status.id);
  if (last) await showJobResult(status.id, last);
}

async function run() {
  if (state.busy) return;
  lockRun(true);
  try {
    let extra;
    try { extra = JSON.parse($("extra").value || "{}"); } catch (error) { throw new ApiProblem(422, `/extra: not JSON (${error.message})`, "/extra"); }
    await draw();
    clearFrames();
    const choice = currentChoice();
    const request = buildRequest(choice, $("options"), state.doc, $("model").value, extra);
    state.overrides = request.overrides || {};
    state.design = null; // an optimum found before is not this run's
    clearResults("Running: the outputs show when the first result comes.");
    $("job").hidden = true; // an earlier job's progress is not this run's
    state.running = { source: choice.kind === "solve" ? `solve:${choice.analysis}` : `job:${choice.job}`, title: choice.label };
    showCard(state.running.source, choice.label, "running", null);
    revealCard();
    say("run-state", `${choice.label}: running…`, "running");
    if (choice.kind === "solve") await runSolve(choice, request);
    else await runJob(choice, request);
  } catch (error) {
    report(error);
  } finally {
    state.running = null;
    lockRun(false);
  }
}

async function cancelJob() {
  if (!state.jobId) return;
  try { await cancel(state.jobId); say("run-state", "cancelling…", "cancelled"); } catch (error) { report(error); }
}

// The analyses (with their options' schemas) and the job kinds (the API's own schema).
async function offered() {
  const [analyses, openapi, kinds] = await Promise.all([get("/v1/analyses"), get("/openapi.json"), get("/v1/job-kinds")]);
  state.jobKinds = kinds;
  return choices(analyses, openapi);
}

async function examples() {
  const list = await get("/v1/examples");
  $("example-select").replaceChildren(...list.map((e) => { const o = new Option(e.name, e.name); o.title = e.title; return o; }));
  return list;
}

// A job's page: its document and model, the menus and the form set to what it was asked (its
// request's own options, not the document's), its progress, results as they come and the whole
// result at its end. Run waits until the job ends.
async function followJobPage(id) {
  lockRun(true);
  try {
    const asked = await jobRequest(id);
    state.overrides = asked.overrides || {};
    setText(JSON.stringify(asked.document, null, 2));
    if (asked.model) $("model").value = asked.model;
    const extra = Object.fromEntries(["overrides", "options"].filter((key) => asked[key] && Object.keys(asked[key]).length).map((key) => [key, asked[key]]));
    $("extra").value = JSON.stringify(extra);
    const example = [...$("example-select").options].find((o) => o.title === asked.document.name);
    $("example-select").value = example ? example.value : "";
    state.example = $("example-select").value;
    await redraw();
    const kind = state.jobKinds.find((k) => k.name === asked.kind);
    const choice = kind && state.choices.find((c) => c.endpoint === kind.route);
    offerChoices(choice ? choice.id : null, false, asked);
    state.jobId = id;
    state.running = { source: `job:${asked.kind}`, title: `${asked.kind.replace(/_/g, " ")} job` };
    showCard(state.running.source, state.running.title, "running", null);
  } catch (error) {
    lockRun(false);
    throw error;
  }
  followToTheEnd(id).catch(report).finally(() => lockRun(false)); // the page is ready while the job goes on
}

async function followToTheEnd(id) {
  const last = await follow(id, partialResults(id), () => state.jobId === id);
  if (last) await showJobResult(id, last);
  state.running = null;
}

function wire() {
  $("api-key").value = apiKey();
  $("api-key").addEventListener("change", () => {
    setApiKey($("api-key").value.trim());
    if (!state.loaded) start(); // the first load needed the key
  });
  $("open-example").addEventListener("click", () => {
    const name = $("example-select").value;
    if (!mayReplaceText(`the example ${name}`)) { $("example-select").value = state.example; return; }
    if (location.pathname !== "/" || new URLSearchParams(location.search).get("example") !== name) history.pushState({ example: name }, "", `/?example=${encodeURIComponent(name)}`);
    openExample(name).catch(report);
  });
  window.addEventListener("popstate", () => location.reload()); // back and forward: the page of that address
  $("draw").addEventListener("click", () => redraw());
  $("run").addEventListener("click", run);
  $("cancel").addEventListener("click", cancelJob);
  $("analysis").addEventListener("change", () => { renderForm($("options"), currentChoice(), state.doc); });
  $("upload").addEventListener("change", async () => {
    const file = $("upload").files[0];
    if (file && !mayReplaceText(file.name)) { $("upload").value = ""; return; }
    if (file) { newDocument(); setText(await file.text()); state.example = ""; await redraw(true); }
  });
  let timer = null;
  $("editor").addEventListener("input", () => { clearTimeout(timer); timer = setTimeout(redraw, REDRAW_AFTER_MS); });
  for (const id of ["curve-x", "curve-y"]) $(id).addEventListener("change", () => renderCurve(state.view));
  wireAnimation();
  wireDownloads(state);
  wireFabrication(state, (message) => say("run-state", message, "error"));
  wireTabs(() => { renderCurve(state.view); renderEnergies(state.view); });
  wireCompare(() => state.view, () => renderCurve(state.view));
  wirePickers($("drawing"));
}

// Examples, analyses, then the example asked for (?example=) or the job of the address.
async function load() {
  const [offer] = await Promise.all([offered(), examples()]);
  state.choices = offer;
  $("analysis").replaceChildren(...state.choices.map((c) => new Option(c.label, c.id)));
  showRecentJobs();
  const job = location.pathname.match(/^\/jobs\/([0-9a-f]{32})$/);
  const wanted = new URLSearchParams(location.search).get("example") || DEFAULT_EXAMPLE;
  state.loaded = true;
  if (job) await followJobPage(job[1]);
  else await openExample(wanted);
}

async function start() {
  try { await load(); } catch (error) { report(error); }
  document.body.dataset.ready = "true";
}

wire();
start();
