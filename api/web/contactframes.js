// A contact state as a frame of the drawing (scene.js): the links' surfaces, the jaws and the
// objects where the state puts them, each touching pair's force as an arrow ending at its
// contact point, and the bodies at the links' ends.

import { posesAtElementEnds } from "./scene.js";
import { numberText } from "./display.js";

const CONTACT_COLOURS = { link: "#0b62a4", jaw: "#1d2430", object: "#c46a00" };

export function contactFrame(point, label, base, forceUnit = "") {
  const drawing = point.drawing || { links: [], jaws: [], objects: [] };
  const lines = [];
  for (const link of drawing.links) {
    lines.push({ points: link.left, color: CONTACT_COLOURS.link }, { points: link.right, color: CONTACT_COLOURS.link },
               { points: link.centre, color: CONTACT_COLOURS.link, dashed: true, width: "0.8" });
  }
  for (const jaw of drawing.jaws) lines.push({ points: jaw.points, closed: jaw.closed, color: CONTACT_COLOURS.jaw, width: "2" });
  for (const object of drawing.objects) lines.push({ points: object.points, closed: object.closed, color: CONTACT_COLOURS.object, fill: object.type === "hole" ? "none" : "#f6e3cc", bounded: object.closed });
  const forces = Object.entries(point.pairs || {}).filter(([, p]) => p.point && p.state !== "open")
    .map(([name, p]) => ({ point: p.point, vector: p.force, label: `${name} ${numberText(Math.hypot(...p.force))} ${forceUnit}` }));
  const centres = Object.fromEntries(drawing.links.map((link) => [link.name, link.centre]));
  return { elements: centres, poses: base ? posesAtElementEnds(base, centres) : {}, about: "reference", hideElements: true,
           overlay: { lines, forces, replaces: drawing.objects.map((o) => o.name) }, label };
}

