"""Comparing surfaces: sampling two on one grid, and the distances between them."""
