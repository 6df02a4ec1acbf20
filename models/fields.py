"""Field types shared by every part of the mechanism document (and by element families)."""

from __future__ import annotations

from typing import Union

from pydantic import BaseModel, ConfigDict

Number = Union[float, str]
Vec2 = tuple[Number, Number]


class StrictModel(BaseModel):
    """A document object: unknown fields are errors, and aliases ("from") are accepted."""

    model_config = ConfigDict(extra="forbid", populate_by_name=True)
