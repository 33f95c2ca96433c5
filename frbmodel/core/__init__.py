"""Core services: exception types and range checks, units, progress, interruption, small dense linear algebra, the
result base class."""
