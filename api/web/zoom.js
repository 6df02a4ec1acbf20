// Zoom and pan of a drawing (scene.js): the mouse wheel zooms about the cursor, a drag pans, and
// the buttons +, − and 0 (keyboard reachable) zoom in, out and back to the whole drawing. The
// view is a factor and a shift over the bounds the drawing is given, so it stays while an
// animation's frames play (their bounds are fixed: animation.js); another mechanism (bodies and
// elements by other names) starts from the whole drawing again, as resetView does.

const STEP = 1.5; // a button's zoom
const LIMITS = [0.25, 200];
const DRAG = 3; // pixels a press moves before it pans (a click picks: pickers.js)

const views = new WeakMap(); // container -> {zoom, shift: [dx, dy] (drawing units), key, redraw, view, svg}

function stateOf(container) {
  let state = views.get(container);
  if (!state) {
    state = { zoom: 1, shift: [0, 0], key: null, redraw: null, view: null, svg: null, base: null };
    views.set(container, state);
    wire(container, state);
  }
  return state;
}

function mechanismKey(drawing) {
  return JSON.stringify([drawing.name, Object.keys(drawing.bodies || {}), (drawing.elements || []).map((e) => e.name)]);
}

// The bounds to draw for `bounds` (the whole drawing), as the container's view zooms and pans
// them; `redraw()` draws again (the latest call's drawing and frame).
export function viewedBounds(container, drawing, bounds, redraw) {
  const state = stateOf(container);
  const key = mechanismKey(drawing);
  if (key !== state.key) Object.assign(state, { zoom: 1, shift: [0, 0], key });
  state.redraw = redraw;
  state.base = bounds;
  if (state.zoom === 1 && !state.shift[0] && !state.shift[1]) return bounds; // the whole drawing, exactly (scene.js clips only a zoomed view)
  const cx = (bounds[0] + bounds[2]) / 2 + state.shift[0], cy = (bounds[1] + bounds[3]) / 2 + state.shift[1];
  const hx = (bounds[2] - bounds[0]) / 2 / state.zoom, hy = (bounds[3] - bounds[1]) / 2 / state.zoom;
  return [cx - hx, cy - hy, cx + hx, cy + hy];
}

// What was drawn: the view (scene.js transform: map, unmap, scale) and its SVG, for the pointer's
// place in drawing units.
export function drawn(container, view, svg) {
  const state = stateOf(container);
  state.view = view;
  state.svg = svg;
  svg.dataset.zoom = String(state.zoom);
  svg.dataset.view = view.visible.map((v) => Number(v.toPrecision(6))).join(" ");
}

export function resetView(container) {
  const state = stateOf(container);
  Object.assign(state, { zoom: 1, shift: [0, 0] });
  if (state.redraw) state.redraw();
}

// Zoom by `factor` about the drawing point `at` (default: the middle of the view).
export function zoomBy(container, factor, at = null) {
  const state = stateOf(container);
  if (!state.base) return;
  const zoom = Math.max(LIMITS[0], Math.min(LIMITS[1], state.zoom * factor));
  const k = zoom / state.zoom;
  if (at && k !== 1) {
    const b = state.base, centre = [(b[0] + b[2]) / 2 + state.shift[0], (b[1] + b[3]) / 2 + state.shift[1]];
    state.shift = [0, 1].map((i) => state.shift[i] + (at[i] - centre[i]) * (1 - 1 / k));
  }
  state.zoom = zoom;
  if (state.redraw) state.redraw();
}

// The drawing point under a pointer event, or null.
function pointAt(state, event) {
  if (!state.svg || !state.view || !state.svg.isConnected) return null;
  const matrix = state.svg.getScreenCTM();
  if (!matrix) return null;
  const p = new DOMPoint(event.clientX, event.clientY).matrixTransform(matrix.inverse());
  return state.view.unmap([p.x, p.y]);
}

function wire(container, state) {
  container.addEventListener("wheel", (event) => {
    const at = pointAt(state, event);
    if (!at) return;
    event.preventDefault();
    zoomBy(container, Math.exp(-Math.max(-300, Math.min(300, event.deltaY)) / 400), at);
  }, { passive: false });
  let drag = null, pending = false;
  container.addEventListener("pointerdown", (event) => {
    if (event.button !== 0 || !state.view) return;
    drag = { x: event.clientX, y: event.clientY, shift: [...state.shift], moving: false, id: event.pointerId };
  });
  container.addEventListener("pointermove", (event) => {
    if (!drag || event.pointerId !== drag.id || !state.svg) return;
    const dx = event.clientX - drag.x, dy = event.clientY - drag.y;
    if (!drag.moving && Math.hypot(dx, dy) < DRAG) return;
    if (!drag.moving) { drag.moving = true; container.setPointerCapture(event.pointerId); container.dataset.panning = "true"; }
    const pixels = state.svg.getScreenCTM().a * state.view.scale; // screen pixels per drawing unit
    state.shift = [drag.shift[0] - dx / pixels, drag.shift[1] + dy / pixels];
    if (!pending) { pending = true; requestAnimationFrame(() => { pending = false; if (state.redraw) state.redraw(); }); }
  });
  const end = () => { drag = null; delete container.dataset.panning; };
  container.addEventListener("pointerup", end);
  container.addEventListener("pointercancel", end);
  addButtons(container);
}

// +, − and 0 beside the drawing (outside it: the drawing is redrawn, the buttons keep focus).
function addButtons(container) {
  const bar = document.createElement("div");
  bar.className = "zoom-controls";
  bar.setAttribute("role", "group");
  bar.setAttribute("aria-label", "Zoom the drawing");
  for (const [text, label, act] of [["+", "Zoom in", () => zoomBy(container, STEP)], ["−", "Zoom out", () => zoomBy(container, 1 / STEP)],
                                     ["0", "Reset zoom: the whole drawing", () => resetView(container)]]) {
    const button = document.createElement("button");
    Object.assign(button, { type: "button", textContent: text, title: label });
    button.setAttribute("aria-label", label);
    button.dataset.zoom = label.split(":")[0].toLowerCase().replace(" ", "-");
    button.addEventListener("click", act);
    bar.append(button);
  }
  container.before(bar);
}
