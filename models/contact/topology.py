"""What of a document's contacts shapes the graphs (no numbers): objects, sites and pairs,
and the convex pieces their polygons split into."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class ObjectTopology:
    name: str
    type: str  # circle | ellipse | polygon | half_plane | implicit
    body: int | None  # carried by this body, or fixed
    pieces: tuple[tuple[int, ...], ...] = ()  # polygon: convex pieces (vertex indices)
    expression: str | None = None  # implicit: g(x, y)

    @property
    def pointer(self) -> str:
        return f"/contacts/objects/{self.name}"


@dataclass(frozen=True)
class SiteTopology:
    name: str
    type: str  # jaw | surface
    body: int | None = None  # jaw on a body
    link: str | None = None  # jaw on a link's end section, or a link's surface
    end: str = "end"
    n_vertices: int = 0
    closed: bool = False
    pieces: tuple[tuple[int, ...], ...] = ()  # jaw: convex pieces (vertex indices)
    side: str = ""  # surface: left | right | centre_line

    @property
    def pointer(self) -> str:
        return f"/contacts/sites/{self.name}"


@dataclass(frozen=True)
class PairTopology:
    name: str
    site: int  # index into ContactTopology.sites
    object: int
    friction_pointer: str = ""  # the coefficient a quasi-static solve slips at (models.contact.schema)
    normal_law: str = "unilateral"  # the laws' names (models.contact.laws): each analysis checks its own
    friction_law: str = "coulomb"
    potential: bool = False  # part of the mechanism's energy (models.contact.elastic_pairs)

    @property
    def pointer(self) -> str:
        return f"/contacts/pairs/{self.name}"


@dataclass(frozen=True)
class ContactTopology:
    objects: tuple[ObjectTopology, ...]
    sites: tuple[SiteTopology, ...]
    pairs: tuple[PairTopology, ...]
