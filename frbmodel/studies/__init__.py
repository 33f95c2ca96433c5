"""Studies over parameters and runs: Dask sweeps, linear vs nonlinear, the paper's figures, compiling the kernels on
purpose."""
