"""The physics kernels: films, finite-length correction, ring torques and RSR, losses, the compiled equations of
motion."""
