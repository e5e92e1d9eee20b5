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
    title = fig.get_suptitle()
    if title:
        # tight_layout lays the panels out as if there were no suptitle, whose lines then overprint
        # the top panels' titles (the sweep's pictures): keep its height free at the top
        # (its lines hang from y = 0.98; below them a panel's own title, ~10 pt with its pad)
        lines = title.count("\n") + 1
        inches = (1.35 * lines * fig._suptitle.get_fontsize() + 24.0) / 72.0
        fig.subplots_adjust(top=min(fig.subplotpars.top, 0.98 - inches / fig.get_figheight()))
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    return buffer.getvalue()
