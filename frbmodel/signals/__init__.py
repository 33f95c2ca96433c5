"""Signals of a run: spectrogram, component tracking, tolerance convergence, orbits and waterfalls."""
