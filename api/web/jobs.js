// Following a job: its progress polled from /v1/jobs/{id} until it finishes, its result read
// a page at a time, and Cancel (DELETE); its request (/request) draws its mechanism on its
// own page (/jobs/{id}).

import { get, post } from "./api.js";

const $ = (id) => document.getElementById(id);
const POLL_MS = 250;
const FINAL = ["succeeded", "failed", "cancelled"];

// What the job was asked (its document and model), for its page to draw the mechanism.
export function jobRequest(id) {
  return get(`/v1/jobs/${id}/request`);
}

export function showProgress(status) {
  const { done, total, fraction, failed_points: failed } = status.progress;
  const percent = Math.round(fraction * 100);
  $("job").hidden = false;
  $("progress").value = percent;
  $("progress-text").textContent = `${status.kind} ${status.status}: ${percent} % (${done} of ${total}${failed ? `, ${failed} not converged` : ""})`;
  $("job-link").href = `/jobs/${status.id}`;
  $("job-link").textContent = `job ${status.id.slice(0, 8)}`;
  $("cancel").disabled = FINAL.includes(status.status);
}

// Every page of the result (a sweep's points come in pages).
export async function fullResult(id) {
  const first = await get(`/v1/jobs/${id}/result`);
  const points = first.result && first.result.points;
  let page = first.page;
  while (page && points && page.returned > 0 && page.returned === page.limit) {
    const next = await get(`/v1/jobs/${id}/result?offset=${points.length}`);
    points.push(...next.result.points);
    page = next.page;
  }
  return first;
}

// Poll until the job is final; resolves its last status. `onTick(status)` runs at each poll;
// when `wanted()` says the page no longer shows the job (another document), polling stops
// and resolves null.
export function follow(id, onTick, wanted = () => true) {
  return new Promise((resolve, reject) => {
    const poll = async () => {
      if (!wanted()) { resolve(null); return; }
      try {
        const status = await get(`/v1/jobs/${id}`);
        if (!wanted()) { resolve(null); return; }
        showProgress(status);
        onTick && onTick(status);
        if (FINAL.includes(status.status)) resolve(status);
        else setTimeout(poll, POLL_MS);
      } catch (error) {
        reject(error);
      }
    };
    poll();
  });
}

export async function cancel(id) {
  const status = await post(`/v1/jobs/${id}/cancel`);
  showProgress(status);
  return status;
}
