"""Tolerances: how a made part scatters about its drawing, what that does to its responses, and its yield."""
