"""Vibration: the natural modes of a mechanism about an equilibrium (modes), and the eigenproblem
they solve (eigen)."""
