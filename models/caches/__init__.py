"""Graphs and other built things kept on disk, keyed by the code that built them."""
