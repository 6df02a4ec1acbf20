"""The structure and its graphs: the collector, the residual, energy and mass forms, outputs, loads, the K_T split."""
