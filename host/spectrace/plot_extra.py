"""matplotlib, which only the figures need, comes with the `plot` extra (`pip install 'spectrace[plot]'`); a
figure asked for without it is one line naming the extra, said before any work."""

from spectrace.errors import SpectraceError

PLOT_EXTRA_HINT = "needs matplotlib, which the plot extra installs: pip install 'spectrace[plot]'"


def require_matplotlib(where: str | None = None) -> None:
    """Refuse, naming `where` (the option or command that draws) and the extra, when matplotlib is missing."""
    try:
        import matplotlib
    except ImportError:
        raise SpectraceError(PLOT_EXTRA_HINT, where=where) from None
    # colour-science puts a stand-in (a MagicMock) where it finds no matplotlib; only the real one has a version.
    if not isinstance(getattr(matplotlib, "__version__", None), str):
        raise SpectraceError(PLOT_EXTRA_HINT, where=where)


def pyplot(where: str | None = None):
    """matplotlib.pyplot on the Agg backend (files only; never a window)."""
    require_matplotlib(where)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot

    return matplotlib.pyplot
