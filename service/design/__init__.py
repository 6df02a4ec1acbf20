"""Design: the design problem, its NLP, the load cases' states, optimization and sensitivities."""
