// What the open document can be asked (the service's offers, drawn with it: service/offers.py)
// and which of it the page chooses first: the analysis the document is written for.

// Why a choice of the Run menu does not apply to the document, or "" when it does.
export function whyNot(choice, offers) {
  if (!offers) return "";
  const reasons = choice.kind === "solve" ? offers.analyses : offers.jobs;
  return (reasons && reasons[choice.kind === "solve" ? choice.analysis : choice.job]) || "";
}

// The first analysis of a document: its simulation (the simulate analysis for an impact
// scheme, which takes milliseconds; a job for link dynamics, which takes seconds), its contact
// state, its optimization, its tolerances, its modes (offered where it has mass), else its equilibrium.
export function defaultChoice(open, doc) {
  const simulate = (doc && doc.simulate) || null;
  const impact = simulate && ["event_driven", "moreau"].includes(simulate.scheme);
  const order = [];
  if (simulate && simulate.until) order.push(impact ? "solve:simulate" : "job:simulation");
  if (doc && doc.contacts && doc.contacts.pairs && Object.keys(doc.contacts.pairs).length) order.push("solve:contact");
  if (doc && doc.optimize) order.push("job:optimization");
  if (doc && doc.tolerances) order.push("solve:tolerance");
  order.push("solve:modes", "solve:equilibrium");
  for (const id of order) {
    const found = open.find((c) => c.id === id);
    if (found) return found;
  }
  return open[0] || null;
}
