"""FMI co-simulation layer: FMU building, the SSP-driven master and the linearization composer.

The only part of frbmodel that imports fmpy / pythonfmu (lazily, inside functions).
"""
