"""Nonlinear time integration: run-ups, the compiled integrators, the streamed results, the steppable components of the
FMUs."""
