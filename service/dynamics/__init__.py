"""Time simulation of mechanisms (seed 002, Ch. 3-4) over the dynamics form (models.graph.dynamics):
the Newmark family and generalized-alpha, each step's implicit system by Newton with the
exact Jacobian."""
