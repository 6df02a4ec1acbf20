"""Element families, one module each, registered here: one line per family.

A family reads its section of the document and contributes its part of every graph (see
models.elements.base for the contract). The document schema, the collector and the
assembly ask this registry; none of them names an element type.
"""

from flexmech.models.elements.base import Families
from flexmech.models.elements.curved_beam import COMPARED_MODELS, CURVED_BEAM, MODELS
from flexmech.models.elements.link import LINK
from flexmech.models.elements.link_elements import LINK_ELEMENTS
from flexmech.models.elements.pin import PIN
from flexmech.models.elements.slider import SLIDER
from flexmech.models.elements.spring import SPRING

FAMILIES = Families(
    [
        CURVED_BEAM,
        LINK,
        LINK_ELEMENTS,
        SPRING,
        PIN,
        SLIDER,
    ]
)

__all__ = ["COMPARED_MODELS", "FAMILIES", "MODELS"]
