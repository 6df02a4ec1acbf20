// The result card at the top of the results: the run's status as a badge (running, succeeded,
// failed, cancelled each in its own style), its headline quantities with units, and its
// warnings styled as warnings. A new run empties it until its own first result.

import { display } from "./display.js";
import { headline } from "./headline.js";

const $ = (id) => document.getElementById(id);

// Every status word of a report or a job, by the style it is shown in.
const STYLES = {
  running: ["running", "queued", "pending", "cancelling"],
  ok: ["converged", "finished", "succeeded", "completed"],
  cancelled: ["cancelled", "stopped"],
};

export function statusStyle(status) {
  for (const [style, words] of Object.entries(STYLES)) if (words.includes(status)) return style;
  return "failed";
}

// A number as the card shows it: in its quantity's display unit with six significant digits
// (display.js, the command line's rules: 1.2e-9 kg is 1.21946 ug, 77.0346 uN on every card);
// a count as itself.
function shownAs(item) {
  if (Number.isInteger(item.value) && !item.unit && Math.abs(item.value) < 1e6) return { text: String(item.value), unit: "" };
  const shown = display(item.unit || "", [item.value], item.kind || null);
  return { text: shown.text(item.value), unit: shown.unit };
}

function badge(status) {
  const element = document.createElement("span");
  element.className = `badge status-${statusStyle(status)}`;
  element.id = "result-status";
  element.textContent = status.replace(/_/g, " ");
  return element;
}

function itemOf(item) {
  const box = document.createElement("div");
  box.className = "headline-item";
  if (item.id) box.id = item.id;
  const name = document.createElement("dt");
  name.textContent = item.name;
  const value = document.createElement("dd");
  const number = document.createElement("strong");
  const shown = shownAs(item);
  number.textContent = shown.text;
  if (item.id) number.id = `${item.id}-value`;
  value.append(number);
  if (shown.unit) {
    const unit = document.createElement("span");
    unit.className = "unit";
    unit.textContent = ` ${shown.unit}`;
    value.append(unit);
  }
  box.append(name, value);
  if (item.note) {
    const note = document.createElement("dd");
    note.className = "note";
    note.textContent = item.note;
    box.append(note);
  }
  return box;
}

function warningsOf(warnings) {
  const list = document.createElement("ul");
  list.className = "warnings";
  list.setAttribute("aria-label", "Warnings");
  for (const text of warnings) {
    const item = document.createElement("li");
    item.className = "warning";
    item.textContent = text;
    list.append(item);
  }
  return list;
}

// `title` names the run ("equilibrium", "sweep job"); `result` null while it runs.
export function showCard(source, title, status, result, detail = "") {
  const card = $("result-card");
  card.hidden = false;
  card.dataset.status = statusStyle(status);
  const head = document.createElement("div");
  head.className = "card-head";
  const name = document.createElement("span");
  name.className = "card-title";
  name.textContent = title;
  head.append(badge(status), name);
  if (detail) {
    const more = document.createElement("span");
    more.className = "card-detail";
    more.textContent = detail;
    head.append(more);
  }
  card.replaceChildren(head);
  if (!result) return;
  const { items, warnings } = headline(source, result);
  if (items.length) {
    const list = document.createElement("dl");
    list.className = "headline";
    list.append(...items.map(itemOf));
    card.append(list);
  }
  if (result.message && statusStyle(status) !== "ok") {
    const message = document.createElement("p");
    message.className = "card-message";
    message.textContent = result.message;
    card.append(message);
  }
  if (warnings.length) card.append(warningsOf(warnings));
}

export function clearCard() {
  $("result-card").hidden = true;
  delete $("result-card").dataset.status;
  $("result-card").replaceChildren();
}
