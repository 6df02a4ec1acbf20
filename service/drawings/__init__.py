"""Drawings and figures: the mechanism as data for the page, outlines, paths, and the plots of the CLI."""
