"""Periodic orbits: shooting, whirl limit cycles, continuation and bifurcations."""
