// The /v1 API as the page uses it: JSON in and out, the API key in X-API-Key (kept in the
// browser's local storage), and errors as ApiProblem carrying the pointer the server names
// and every problem it lists ({pointer, message}, the named one first; that one alone if none).

const KEY_STORE = "flexmech.apiKey";

export class ApiProblem extends Error {
  constructor(status, message, pointer, problems = null) {
    super(message);
    this.status = status;
    this.pointer = pointer || null;
    this.problems = problems && problems.length ? problems : [{ pointer: this.pointer, message }];
  }
}

export function apiKey() {
  return localStorage.getItem(KEY_STORE) || "";
}

export function setApiKey(key) {
  if (key) localStorage.setItem(KEY_STORE, key);
  else localStorage.removeItem(KEY_STORE);
}

async function call(method, path, body) {
  const headers = { Accept: "application/json" };
  if (apiKey()) headers["X-API-Key"] = apiKey();
  if (body !== undefined) headers["Content-Type"] = "application/json";
  let response;
  try {
    response = await fetch(path, { method, headers, body: body === undefined ? undefined : JSON.stringify(body) });
  } catch (error) {
    throw new ApiProblem(0, `the service did not answer (${error.message})`, null);
  }
  const text = await response.text();
  let data = null;
  try { data = text ? JSON.parse(text) : null; } catch { data = null; }
  if (!response.ok) {
    const problem = (data && data.error) || {};
    throw new ApiProblem(response.status, problem.message || `${response.status} ${response.statusText}`, problem.pointer,
                         problem.problems);
  }
  return data;
}

// A file the service sends (a job's archive; a drawing for fabrication, asked by POST with a
// body): its bytes and the name it gives in Content-Disposition.
export async function getFile(path, body = null) {
  const headers = apiKey() ? { "X-API-Key": apiKey() } : {};
  if (body) headers["Content-Type"] = "application/json";
  const response = await fetch(path, body ? { method: "POST", headers, body: JSON.stringify(body) } : { headers });
  if (!response.ok) {
    let message = `${response.status} ${response.statusText}`;
    try { message = (await response.json()).error.message || message; } catch { /* not JSON */ }
    throw new ApiProblem(response.status, message, null);
  }
  const named = /filename="([^"]+)"/.exec(response.headers.get("Content-Disposition") || "");
  return { blob: await response.blob(), name: named ? named[1] : "download" };
}

export const get = (path) => call("GET", path);
export const post = (path, body) => call("POST", path, body);
export const remove = (path) => call("DELETE", path);

// A pointer of the request body into the document: /document/elements/c/to -> /elements/c/to.
export function documentPointer(pointer) {
  if (!pointer) return null;
  if (pointer === "/document") return "";
  return pointer.startsWith("/document/") ? pointer.slice("/document".length) : null;
}
