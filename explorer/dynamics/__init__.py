"""Elastic valve-train dynamics: one model, several interchangeable solvers (see model.solve)."""
