"""Time simulation of rigid bodies on flexures with contact impacts and friction (seed 004):
event-driven Dormand-Prince steps with located contact and friction events, and Moreau-Jean
time stepping; both run as compiled CasADi chunks of steps."""
