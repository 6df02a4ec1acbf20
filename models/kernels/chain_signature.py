"""What shapes a link's element kernel (models.kernels.link_chain) and how its data is laid out:
the chain signature that names and sizes a kernel, and the order of one element's data vector.
Kept apart from the kernel's equations so that the modules that only size, key or fill kernels
(layouts, data, caches, build queues) need not import them."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

from flexmech.models.kernels.rules import ElementPoints, element_points

NODE = 8  # rho, v, a, F: 2 each


@dataclass(frozen=True)
class ChainSignature:
    """What shapes the element kernel: the rotation's degree, the strains, the point rule."""

    degree: int
    shear: bool
    axial: bool
    rule: str = "interpolated"

    @property
    def n_c(self) -> int:
        return (self.degree + 1) + self.degree * (int(self.shear) + int(self.axial))

    @property
    def n_local(self) -> int:
        """Unknowns of one element: its coordinates, then node e's and node e+1's quantities."""
        return self.n_c + 2 * NODE

    @property
    def n_rows(self) -> int:
        return self.n_c + 8

    @property
    def key(self) -> str:
        return f"chain_p{self.degree}{'s' if self.shear else ''}{'a' if self.axial else ''}_{self.points.key}"

    @cached_property
    def points(self) -> ElementPoints:
        return element_points(self.degree, self.rule)

    @property
    def n_data(self) -> int:
        return sum(size for _, size in data_layout(self))


def data_layout(signature: ChainSignature) -> list[tuple[str, int]]:
    """(name, size) of one element's data vector, in order: everything that does not change
    in time (geometry, section, material), computed once from the parameters."""
    ns, nq = len(signature.points.xi), len(signature.points.quad_xi)
    return [
        ("du", 1),
        ("length", 1),
        ("eta_points", ns),
        ("eta_quad", nq),
        ("EI", nq),
        ("kGA", nq),
        ("EA", nq),
        ("mass", nq),
        ("rotary", nq),
        ("undeformed_increment", 2),
    ]


def split_data(signature: ChainSignature, data) -> dict:
    out, k = {}, 0
    for name, size in data_layout(signature):
        out[name] = data[k : k + size]
        k += size
    return out
