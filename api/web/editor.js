// The document editor (CodeMirror 6, bundled in vendor/codemirror.js): its text, JSON or YAML,
// read into a document; every problem listed under it and marked at its line (underlined,
// with its message at the line's end and in the gutter), its field selected on request; field
// names completed from the document's schema (completion.js).

import { ApiProblem, post } from "./api.js";
import { fieldNames } from "./completion.js";
import { isJson, locate } from "./pointers.js";
import {
  Compartment, Decoration, EditorState, EditorView, StateEffect, StateField, WidgetType, autocompletion, bracketMatching,
  closeBrackets, closeBracketsKeymap, completionKeymap, defaultHighlightStyle, defaultKeymap, drawSelection, foldGutter,
  foldKeymap, forEachDiagnostic, highlightActiveLine, highlightActiveLineGutter, highlightSelectionMatches,
  highlightSpecialChars, history, historyKeymap, indentOnInput, json, keymap, lineNumbers, lintGutter, lintKeymap,
  searchKeymap, setDiagnostics, syntaxHighlighting, yaml,
} from "./vendor/codemirror.js";

const JSON_LANGUAGE = json(), YAML_LANGUAGE = yaml();
const language = new Compartment();
let quiet = false; // text set by the page, not typed: no "input" event
let opened = ""; // the text the page last set (an example, an upload, a job's document)

// The language follows the text: JSON when it starts with "{", YAML otherwise.
const languageOfText = EditorState.transactionExtender.of((tr) => {
  if (!tr.docChanged) return null;
  const wanted = isJson(tr.newDoc.sliceString(0, 1000)) ? JSON_LANGUAGE : YAML_LANGUAGE;
  return language.get(tr.startState) === wanted ? null : { effects: language.reconfigure(wanted) };
});

// Each problem's message written at the end of its line.
class Note extends WidgetType {
  constructor(text) { super(); this.text = text; }
  eq(other) { return other.text === this.text; }
  toDOM() {
    const note = document.createElement("span");
    note.className = "cm-problem-note";
    note.textContent = this.text;
    return note;
  }
}

const setNotes = StateEffect.define();
const notes = StateField.define({
  create: () => Decoration.none,
  update(value, tr) {
    for (const effect of tr.effects) if (effect.is(setNotes)) return effect.value;
    return value.map(tr.changes);
  },
  provide: (field) => EditorView.decorations.from(field),
});

// Changes made in the editor (typing, completion, undo, paste) told to the page as "input".
const told = EditorView.updateListener.of((update) => {
  if (update.docChanged && !quiet) update.view.contentDOM.dispatchEvent(new Event("input", { bubbles: true }));
});

const view = new EditorView({
  parent: document.getElementById("editor-view"),
  state: EditorState.create({
    doc: "",
    extensions: [
      lineNumbers(), foldGutter(), lintGutter(), highlightActiveLineGutter(), highlightSpecialChars(), history(),
      drawSelection(), indentOnInput(), syntaxHighlighting(defaultHighlightStyle, { fallback: true }), bracketMatching(),
      closeBrackets(), autocompletion({ override: [fieldNames], icons: false }), highlightActiveLine(),
      highlightSelectionMatches(), language.of(JSON_LANGUAGE), languageOfText, notes, told,
      keymap.of([...closeBracketsKeymap, ...defaultKeymap, ...searchKeymap, ...historyKeymap, ...foldKeymap,
                 ...completionKeymap, ...lintKeymap]),
      EditorView.contentAttributes.of({ id: "editor", "aria-label": "Mechanism document, JSON or YAML",
                                        "aria-describedby": "problems" }),
    ],
  }),
});

export function setText(source) {
  opened = source;
  quiet = true;
  try {
    view.dispatch({ changes: { from: 0, to: view.state.doc.length, insert: source }, selection: { anchor: 0 }, scrollIntoView: true });
  } finally {
    quiet = false;
  }
}

export function text() {
  return view.state.doc.toString();
}

// Whether the text differs from what the page last opened: edits that exist nowhere else.
export function edited() {
  return text() !== opened;
}

// Where JSON.parse stopped ("... at position 42 ...", else the end of the text).
function jsonErrorAt(source, error) {
  const position = /at position (\d+)/.exec(error.message);
  return Math.min(position ? Number(position[1]) : source.length, source.length);
}

// Where the service's YAML reader stopped ("line 3, column 5" of its message), or null.
function yamlErrorAt(message) {
  const where = /line (\d+), column (\d+)/.exec(message);
  if (!where || Number(where[1]) > view.state.doc.lines) return null;
  const line = view.state.doc.line(Number(where[1]));
  return Math.min(line.from + Number(where[2]) - 1, line.to);
}

// The document in the editor; JSON is read here, YAML by the service (the page has no YAML reader).
export async function readDocument() {
  const source = text();
  if (isJson(source)) {
    try {
      return JSON.parse(source);
    } catch (error) {
      const message = `the document is not valid JSON: ${error.message}`;
      throw new ApiProblem(422, message, "", [{ pointer: "", message, at: jsonErrorAt(source, error) }]);
    }
  }
  try {
    return (await post("/v1/documents/parse", { text: source, format: "yaml" })).document;
  } catch (error) {
    const at = error instanceof ApiProblem && error.pointer === "/text" ? yamlErrorAt(error.message) : null;
    if (at === null) throw error;
    throw new ApiProblem(error.status, error.message, error.pointer, [{ pointer: error.pointer, message: error.message, at }]);
  }
}

function selectRange(from, to) {
  view.dispatch({ selection: { anchor: from, head: to }, effects: EditorView.scrollIntoView(from, { y: "center" }) });
  view.focus();
}

export function select(pointer) {
  const range = locate(text(), pointer);
  if (!range) return false;
  selectRange(range[0], range[1]);
  return true;
}

// Where a problem is marked: the position a reader stopped at, its field, or the nearest
// enclosing field there is (a missing field's object); null for a field not in the text.
function placeOf({ pointer, at }) {
  const length = view.state.doc.length;
  if (at !== undefined && at !== null) return [Math.min(at, length), Math.min(at + 1, length)];
  if (pointer === null || pointer === undefined) return null;
  for (let tokens = pointer.split("/"); tokens.length > 1; tokens.pop()) {
    const range = locate(text(), tokens.join("/"));
    if (range) return range;
  }
  return pointer === "" && length ? [0, 0] : null;
}

const plainMessage = (message) => message.replace(/^\/document[^:]*: /, "").replace(/^\/[^:\s]*: /, "");

// Lint diagnostics and line-end notes of the problems, on the first line of each field.
function markProblems(problems) {
  const diagnostics = [], byLine = new Map();
  for (const problem of problems) {
    const place = placeOf(problem);
    if (!place) continue;
    const line = view.state.doc.lineAt(place[0]);
    const message = plainMessage(problem.message);
    diagnostics.push({ from: place[0], to: Math.max(place[0], Math.min(place[1], line.to)), severity: "error", message,
                       source: problem.pointer || undefined });
    byLine.set(line.from, [...(byLine.get(line.from) || []), message]);
  }
  const marks = [...byLine].flatMap(([from, messages]) => [
    Decoration.line({ class: "cm-problem-line" }).range(from),
    Decoration.widget({ widget: new Note(messages.join("; ")), side: 1 }).range(view.state.doc.lineAt(from).to),
  ]);
  view.dispatch(setDiagnostics(view.state, diagnostics), { effects: setNotes.of(Decoration.set(marks, true)) });
}

// The problems marked in the text now: [{line, message}] (the tests read them).
export function markedProblems() {
  const marked = [];
  forEachDiagnostic(view.state, (d, from) => marked.push({ line: view.state.doc.lineAt(from).number, message: d.message }));
  return marked;
}

// Problems listed under the editor and marked in it; each names its field and can select it.
export function showProblems(problems) {
  const list = document.getElementById("problems");
  list.replaceChildren();
  for (const problem of problems) {
    const { pointer, message, at } = problem;
    const item = document.createElement("li");
    item.className = "problem";
    if (pointer !== null && pointer !== undefined) item.dataset.pointer = pointer;
    const where = document.createElement("code");
    where.textContent = pointer ? pointer : pointer === "" ? "(the document)" : "(the request)";
    const words = document.createElement("span");
    words.className = "problem-message";
    words.textContent = ` ${plainMessage(message)}`;
    item.append(where, words);
    const place = at !== undefined && at !== null ? placeOf(problem) : null;
    if (place || (pointer && locate(text(), pointer))) {
      const show = document.createElement("button");
      show.type = "button";
      show.textContent = "show";
      show.setAttribute("aria-label", `show ${pointer || "the problem"} in the document`);
      show.addEventListener("click", () => (place ? selectRange(place[0], place[0]) : select(pointer)));
      item.append(show);
    }
    list.append(item);
  }
  markProblems(problems);
}
