// Where a JSON pointer's field is in the text of a document, JSON or YAML: the editor selects
// it and marks problems there.

function unescapePointerToken(token) {
  return token.replace(/~1/g, "/").replace(/~0/g, "~");
}

// Where the value at `pointer` starts in JSON text: [start, end) or null. A small scanner
// that follows keys and array indices; strings are skipped whole.
function locateInJson(source, pointer) {
  const tokens = pointer.split("/").slice(1).map(unescapePointerToken);
  let at = 0;
  const skipSpace = () => { while (at < source.length && /\s/.test(source[at])) at++; };
  const readString = () => { const start = at++; while (at < source.length && source[at] !== '"') at += source[at] === "\\" ? 2 : 1; at++; return JSON.parse(source.slice(start, at)); };
  const skipValue = () => {
    skipSpace();
    if (source[at] === '"') { readString(); return; }
    if (source[at] === "{" || source[at] === "[") {
      let depth = 0;
      do {
        if (source[at] === '"') { readString(); continue; }
        if (source[at] === "{" || source[at] === "[") depth++;
        if (source[at] === "}" || source[at] === "]") depth--;
        at++;
      } while (depth > 0 && at < source.length);
      return;
    }
    while (at < source.length && !/[,}\]\s]/.test(source[at])) at++;
  };
  for (const token of tokens) {
    skipSpace();
    const open = source[at];
    if (open !== "{" && open !== "[") return null;
    at++;
    let found = false;
    for (let index = 0; !found; index++) {
      skipSpace();
      if (source[at] === "}" || source[at] === "]" || at >= source.length) return null;
      if (open === "{") {
        const key = readString();
        skipSpace(); at++; // the colon
        if (key === token) { found = true; break; }
      } else if (String(index) === token) { found = true; break; }
      skipValue(); skipSpace();
      if (source[at] === ",") at++;
    }
  }
  skipSpace();
  const start = at;
  skipValue();
  return [start, at];
}

// Where `pointer` is in YAML text (block style): each token a key, or the n-th "- " item,
// indented deeper than the one before.
function locateInYaml(source, pointer) {
  const tokens = pointer.split("/").slice(1).map(unescapePointerToken);
  const lines = source.split("\n");
  const starts = [];
  let total = 0;
  for (const text of lines) { starts.push(total); total += text.length + 1; }
  let line = -1, indent = -1;
  for (const token of tokens) {
    let hit = -1, items = -1;
    for (let i = line + 1; i < lines.length; i++) {
      const current = lines[i].search(/\S/);
      if (current < 0 || lines[i].trim().startsWith("#")) continue;
      if (current <= indent) break;
      const body = lines[i].slice(current);
      if (/^\d+$/.test(token) && body.startsWith("- ")) {
        items++;
        if (String(items) === token) { hit = i; break; }
        continue;
      }
      const key = body.replace(/^- /, "");
      if ([`${token}:`, `"${token}":`, `'${token}':`].some((k) => key.startsWith(k))) { hit = i; break; }
    }
    if (hit < 0) return null;
    line = hit;
    indent = lines[hit].search(/\S/);
  }
  return line < 0 ? null : [starts[line] + indent, starts[line] + lines[line].length];
}

export const isJson = (source) => source.trimStart().startsWith("{");

// Where the field `pointer` names is in `source` (JSON or YAML text): [start, end) or null.
export function locate(source, pointer) {
  if (pointer === null || pointer === undefined) return null;
  if (pointer === "") return [0, 0];
  return isJson(source) ? locateInJson(source, pointer) : locateInYaml(source, pointer);
}
