"""Linear analyses: equilibria, the global linear system, modes, the Campbell diagram, film whirl, mode shapes,
unbalance response."""
