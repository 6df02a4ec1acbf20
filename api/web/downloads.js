// Downloads of what the page shows: the result as JSON, its series or table as CSV, and the
// visible figure (drawing, curve or energies) as SVG or PNG, made in the browser; the document's
// fabricated outlines as DXF or GDS, made by the service.

import { getFile } from "./api.js";
import { svgMarkup, svgToPngBlob } from "./plot.js";

function save(blob, name) {
  const link = document.createElement("a");
  link.href = URL.createObjectURL(blob);
  link.download = name;
  document.body.append(link);
  link.click();
  link.remove();
  setTimeout(() => URL.revokeObjectURL(link.href), 10_000);
}

const slug = (text) => (text || "flexmech").toLowerCase().replace(/[^a-z0-9]+/g, "-").replace(/^-|-$/g, "").slice(0, 60);

// The figure of the open tab: the curve (with the runs kept for comparison on it) or the
// energies, else the mechanism; the kept runs' small colour samples are not figures.
function visibleFigure() {
  const tab = document.querySelector('[role=tab][aria-selected=true]');
  const panel = tab && document.getElementById(tab.getAttribute("aria-controls"));
  return (panel && panel.querySelector("svg.line-plot")) || document.querySelector("#drawing svg");
}

export function wireDownloads(state) {
  const name = () => slug(state.name);
  document.getElementById("download-json").addEventListener("click", () =>
    save(new Blob([JSON.stringify(state.result, null, 2)], { type: "application/json" }), `${name()}.json`));
  document.getElementById("download-csv").addEventListener("click", () =>
    save(new Blob([state.csv()], { type: "text/csv" }), `${name()}.csv`));
  document.getElementById("download-svg").addEventListener("click", () => {
    const svg = visibleFigure();
    if (svg) save(new Blob([svgMarkup(svg)], { type: "image/svg+xml" }), `${name()}.svg`);
  });
  document.getElementById("download-png").addEventListener("click", async () => {
    const svg = visibleFigure();
    if (svg) save(await svgToPngBlob(svg), `${name()}.png`);
  });
}

// The open document's fabricated outlines as DXF or GDS (POST /v1/drawings/fabrication), with
// the model and overrides the page runs with, and an optimization's design once it shows one.
export function wireFabrication(state, onProblem) {
  for (const format of ["dxf", "gds"]) {
    document.getElementById(`download-${format}`).addEventListener("click", async () => {
      try {
        const model = document.getElementById("model").value || undefined;
        const overrides = { ...(state.overrides || {}), ...(state.design || {}) };
        const file = await getFile("/v1/drawings/fabrication", { document: state.doc, model, overrides, format });
        save(file.blob, file.name);
      } catch (problem) {
        onProblem(problem.message);
      }
    });
  }
}

// A job whose result is files (an export's C library): its archive, fetched with the API key.
// link: the job's links.archive, or null to hide the button.
export function offerArchive(link, onProblem) {
  const button = document.getElementById("download-archive");
  button.hidden = !link;
  button.onclick = !link ? null : async () => {
    try {
      const file = await getFile(link);
      save(file.blob, file.name);
    } catch (problem) {
      onProblem(problem.message);
    }
  };
}
