// The recent jobs of this API key (GET /v1/jobs), newest first: kind, mechanism, status in its
// style and progress (but the page's own job's, shown under Run), each a link to its page
// (/jobs/{id}). Read again while any of them runs.

import { get } from "./api.js";
import { statusStyle } from "./card.js";

const $ = (id) => document.getElementById(id);
const SHOWN = 8;
const REREAD_MS = 3000;

let timer = null;

function itemOf(job) {
  const item = document.createElement("li");
  item.dataset.job = job.id;
  const link = document.createElement("a");
  link.href = `/jobs/${job.id}`;
  link.textContent = `${job.kind.replace(/_/g, " ")}: ${job.name || "mechanism"}`;
  const here = location.pathname === link.pathname;
  if (here) link.setAttribute("aria-current", "page");
  const badge = document.createElement("span");
  badge.className = `badge status-${statusStyle(job.status)}`;
  const percent = Math.round(100 * job.progress.fraction);
  // the job of this page has its progress under Run (one figure, read every poll), not here
  badge.textContent = job.status === "running" && !here ? `running ${percent} %` : job.status;
  const when = document.createElement("time");
  when.dateTime = job.timings.created_at;
  when.textContent = new Date(job.timings.created_at).toLocaleTimeString();
  item.append(link, " ", badge, " ", when);
  return item;
}

export async function showRecentJobs() {
  clearTimeout(timer);
  let jobs;
  try { ({ jobs } = await get(`/v1/jobs?limit=${SHOWN}`)); } catch { return; } // the list is a convenience: a failed read keeps the last one
  $("recent-jobs").hidden = !jobs.length;
  $("recent-list").replaceChildren(...jobs.map(itemOf));
  if (jobs.some((job) => statusStyle(job.status) === "running")) timer = setTimeout(showRecentJobs, REREAD_MS);
}
