"""Elastic valve-train dynamics: one model, several interchangeable solvers (see solvers.solve)."""
