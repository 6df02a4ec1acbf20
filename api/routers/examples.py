"""GET /v1/examples: the example documents."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Path

from flexmech.api.deps import OwnerDep, ServicesDep
from flexmech.api.errors import not_found
from flexmech.api.responses import errors
from flexmech.api.schemas import ExampleSummary

router = APIRouter(prefix="/v1/examples", tags=["examples"])


@router.get(
    "",
    operation_id="list_examples",
    response_model=list[ExampleSummary],
    responses=errors(401),
    summary="The example mechanism documents",
)
async def list_examples(services: ServicesDep, _owner: OwnerDep) -> list[ExampleSummary]:
    return [ExampleSummary(name=e.name, title=e.title, description=e.description) for e in services.examples.all()]


@router.get(
    "/{name}",
    operation_id="get_example",
    response_model=dict[str, Any],
    responses=errors(401, 404),
    summary="One example document, ready to send to /v1/solve or /v1/sweeps",
)
async def get_example(
    services: ServicesDep, _owner: OwnerDep, name: str = Path(max_length=64, pattern=r"^[A-Za-z0-9_.-]+$")
) -> dict[str, Any]:
    example = services.examples.get(name)
    if example is None:
        raise not_found(f"no example '{name}' (examples: {', '.join(services.examples.names()) or 'none'})")
    return example.document
