"""Contact (seed 002, Ch. 6): rigid objects, the sites of a mechanism that may touch them,
and the non-penetration constraints between them (the contact analysis is in service)."""
