"""Solvers: Newton, the equilibrium and energy minimum, IPOPT, the compiled fast path, tangent stiffness and mass, inverse analyses, sweeps and continuation, and reports in document units."""
