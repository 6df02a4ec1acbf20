"""The contact analysis (seed 002, Ch. 6): the minimum of the total potential under
non-penetration, by IPOPT; contact forces from its multipliers; friction as loads in
equilibrium with the shape; quasi-static paths; sensitivities."""
