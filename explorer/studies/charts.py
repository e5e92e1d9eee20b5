"""Off-screen matplotlib figures as PNG bytes: one way for every chart of the studies."""

from __future__ import annotations

import io
from contextlib import contextmanager


@contextmanager
def figure(*grid, **options):
    """A matplotlib figure and its axes (off-screen backend, imported only here), closed however
    the drawing ends."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(*grid, **options)
    try:
        yield fig, axes
    finally:
        plt.close(fig)


def png(fig) -> bytes:
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    return buffer.getvalue()
