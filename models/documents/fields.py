"""Field types shared by every part of the mechanism document (and by element families).

Numbers are read strictly: a JSON number (not true or false, not NaN or Infinity), or a
quantity string with a unit of at most MAX_QUANTITY_CHARS characters (models.units reads it).

Every text of a document is bounded (issue 52): a name (the document's, the key of an object in
a named collection, or a reference to one) by MAX_NAME_CHARS, the description by
MAX_DESCRIPTION_CHARS, a JSON pointer, an output's name, an expression and a unit by theirs. A
text over its bound is refused naming the field and the bound (models.documents.text_bounds).
"""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field, StringConstraints

from flexmech.models.units import MAX_UNIT_CHARS

MAX_NAME_CHARS = 200  # a name: the document's, a body's, an element's, a load's, a material's, ...
MAX_DESCRIPTION_CHARS = 20_000  # the document's description: the longest text a document holds
MAX_POINTER_CHARS = 256  # a JSON pointer to a field (/elements/<name>/length: a name and more)
MAX_OUTPUT_CHARS = 256  # an output's name: end_effector.x, reactions.tip.Fy, frequency.1, response(...)
MAX_EXPRESSION_CHARS = 2000  # a safe math expression (models.documents.expression)
MAX_QUANTITY_CHARS = 100  # a number with its unit, "25 um"

Name = Annotated[str, StringConstraints(max_length=MAX_NAME_CHARS)]
Description = Annotated[str, StringConstraints(max_length=MAX_DESCRIPTION_CHARS)]
Pointer = Annotated[str, StringConstraints(max_length=MAX_POINTER_CHARS)]
OutputName = Annotated[str, StringConstraints(max_length=MAX_OUTPUT_CHARS)]
Expression = Annotated[str, StringConstraints(max_length=MAX_EXPRESSION_CHARS)]
UnitName = Annotated[str, StringConstraints(max_length=MAX_UNIT_CHARS)]

Number = (
    Annotated[float, Field(strict=True, allow_inf_nan=False)]
    | Annotated[str, StringConstraints(strict=True, max_length=MAX_QUANTITY_CHARS)]
)
Vec2 = tuple[Number, Number]


class StrictModel(BaseModel):
    """A document object: unknown fields are errors, aliases ("from") are accepted, and no
    float is NaN or infinite."""

    model_config = ConfigDict(extra="forbid", populate_by_name=True, allow_inf_nan=False)
