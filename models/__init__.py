"""Physics of planar compliant mechanisms: the mechanism document and CasADi graph builders.

Public surface:
    load_document(path_or_dict) -> MechanismDocument   (validated, units resolved lazily)
    compile_mechanism(document, model=None) -> Mechanism (numbers as parameters, CasADi Functions)
    MechanismError: every problem with a document, naming the field by JSON pointer.
"""

from flexmech.models.documents.document import MechanismDocument, load_document
from flexmech.models.elements import COMPARED_MODELS, MODELS
from flexmech.models.errors import MechanismError
from flexmech.models.graph.mechanism import Mechanism, compile_mechanism

__all__ = [
    "MechanismError",
    "MechanismDocument",
    "load_document",
    "Mechanism",
    "compile_mechanism",
    "COMPARED_MODELS",
    "MODELS",
]
