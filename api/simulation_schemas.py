"""The request of a simulation job (POST /v1/simulations) as the client sends it: the server
checks `simulate` against the simulate analysis' options (service.analyses.simulate)."""

from __future__ import annotations

from typing import Any

from pydantic import ConfigDict, Field

from api.schemas import DocumentRequest

SIMULATION_EXAMPLES = [
    {"example": "spinning_rod_case1", "simulate": {"until": 2.0, "step": 0.01}},
    {"example": "four_bar_dynamics", "simulate": {"until": 0.1}},
    {"example": "spinning_rod_case1", "simulate": {"until": 1e9, "step": 1e-6}},
]


class SimulationRequest(DocumentRequest):
    """A job: a time simulation by the document's `simulate` section (with `simulate` over
    it), stored per time window as it runs."""

    model_config = ConfigDict(json_schema_extra={"examples": SIMULATION_EXAMPLES})

    simulate: dict[str, Any] | None = Field(
        None,
        description="fields of the document's `simulate` section (until, "
        "step, scheme, rho_inf, a1, a2, damping, start, histories, every, "
        "outputs) that override it",
    )
