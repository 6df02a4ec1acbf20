"""Rigid bodies on flexures with clearance impacts and friction (seed 004): the rigid system
and the geometry of the document's contact pairs between bodies (their laws come from
models.contact.laws), as the CasADi graphs that service.impacts integrates (event-driven or
Moreau-Jean)."""
