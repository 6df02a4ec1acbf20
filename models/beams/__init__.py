"""Beam kernels: the curved beam in closed form, links by shooting, by finite elements, their inverse."""
