"""Rigid bodies on flexures with clearance impacts and friction (seed 004): the document's
`impacts` section, contact-pair geometry, normal and friction laws, and the rigid system's
CasADi graphs that service.impacts integrates (event-driven or Moreau-Jean)."""
