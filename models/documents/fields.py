"""Field types shared by every part of the mechanism document (and by element families).

Numbers are read strictly: a JSON number (not true or false, not NaN or Infinity), or a
quantity string with a unit of at most MAX_QUANTITY_CHARS characters (models.units reads it).
"""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field, StringConstraints

MAX_QUANTITY_CHARS = 100

Number = (
    Annotated[float, Field(strict=True, allow_inf_nan=False)]
    | Annotated[str, StringConstraints(strict=True, max_length=MAX_QUANTITY_CHARS)]
)
Vec2 = tuple[Number, Number]


class StrictModel(BaseModel):
    """A document object: unknown fields are errors, aliases ("from") are accepted, and no
    float is NaN or infinite."""

    model_config = ConfigDict(extra="forbid", populate_by_name=True, allow_inf_nan=False)
