// The names an engineer reads on axes, curves, tables and frames: a document field's JSON
// pointer said in words (its item's name, the field, x or y for a vector's component), e.g.
// /loads/actuation/force/1 -> "actuation force y", /sections/flexure/h -> "flexure h",
// /contacts/objects/fixture/centre/0 -> "fixture centre x". The pointer itself stays the
// series' key, the menus' value and the CSV's header (exact); only what is shown changes.

// The document's fields that are [x, y] pairs (models.documents: Vec2): their 0 and 1 are x and y.
const VECTORS = new Set(["force", "position", "center_of_mass", "at", "offset", "gravity", "center", "centre", "from_at",
                         "to_at", "semi_axes", "point", "normal"]);
// Sections whose entries are named groups of their own (contacts: {objects: {fixture: ...}}).
const NESTED = { contacts: new Set(["objects", "pairs", "sites"]) };

const unescaped = (part) => part.replace(/~1/g, "/").replace(/~0/g, "~");

// A field's pointer in words; anything that is not a pointer is returned as it is.
export function fieldName(pointer) {
  if (typeof pointer !== "string" || !pointer.startsWith("/")) return pointer ?? "";
  const parts = pointer.split("/").slice(1).map(unescaped);
  const last = parts.length - 1;
  if (last >= 1 && /^[01]$/.test(parts[last]) && VECTORS.has(parts[last - 1])) parts[last] = "xy"[Number(parts[last])];
  if (parts.length > 2) { // the section is said by the item's name ("actuation", "flexure")
    const section = parts.shift();
    if (parts.length > 2 && NESTED[section] && NESTED[section].has(parts[0])) parts.shift();
  }
  return parts.join(" ");
}

// A series' name as shown: its own `names` entry (a view may name a series), else its field in words.
export function seriesName(v, name) {
  return (v && v.names && v.names[name]) || fieldName(name);
}

// A series' label on an axis, a menu or a column: its name and unit, "actuation force y [uN]".
export function seriesLabel(v, name) {
  const unit = v && v.units ? v.units[name] : "";
  return unit ? `${seriesName(v, name)} [${unit}]` : seriesName(v, name);
}
