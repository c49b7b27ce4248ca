"""A fixed layout for the report figures: rows of panels placed in inches.

matplotlib's constrained layout measures every tick label of every panel (a text layout each)
before it draws them again, which was over half the CPU of ``check --plot`` on a small capture.
The figures here have a known shape (a title over each panel, tick labels and an x label under
it, a y label and tick labels left of it), so each panel gets fixed room in inches instead; the
tests draw each figure and check that every text stays inside the figure and off the panels.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = [
    "Row",
    "WIDTH_IN",
    "figure_bytes",
    "figure_height",
    "fixed_titles",
    "place_rows",
    "suptitle",
]

#: The figure's width (inches).
WIDTH_IN = 11.0
#: Room above a panel for its title, below it for its tick labels and x label (inches).
TITLE_IN = 0.34
BELOW_IN = 0.52
#: Room left of the first panel (role names, y tick labels, y label), right of the last, and
#: between two panels of a row (the right one's y tick labels and y label) (inches).
LEFT_IN = 1.0
RIGHT_IN = 0.25
GAP_IN = 1.0
#: Where the axis labels go: the x label's top this far under the panel (below its tick labels),
#: the y label's edge this far left of it (left of tick labels up to "1,000,000" at 8 pt).
X_LABEL_IN = 0.27
Y_LABEL_IN = 0.66
#: The figure title: room per line and above it (inches).
SUPTITLE_LINE_IN = 0.26
SUPTITLE_PAD_IN = 0.12
BOTTOM_IN = 0.08


@dataclass(frozen=True)
class Row:
    """A row of ``panels`` panels side by side, each ``height_in`` inches high (the axes alone)."""

    height_in: float
    panels: int = 1


def figure_height(rows: list[Row], title_lines: int) -> float:
    """The height (inches) of a figure of ``rows`` under a title of ``title_lines`` lines."""
    top = SUPTITLE_PAD_IN + SUPTITLE_LINE_IN * title_lines
    return top + sum(TITLE_IN + r.height_in + BELOW_IN for r in rows) + BOTTOM_IN


def place_rows(fig: Figure, rows: list[Row], title_lines: int) -> list[list[Axes]]:
    """Add the panels of ``rows`` to ``fig`` (sized by :func:`figure_height`), top to bottom;
    the panels of each row. Their titles and axis labels have fixed places too (matplotlib
    would otherwise lay out every tick label again to place them): draw inside
    :func:`fixed_titles`."""
    width, height = fig.get_size_inches()
    y = height - SUPTITLE_PAD_IN - SUPTITLE_LINE_IN * title_lines
    out = []
    for r in rows:
        y -= TITLE_IN + r.height_in
        each = (width - LEFT_IN - RIGHT_IN - GAP_IN * (r.panels - 1)) / r.panels
        out.append(
            [
                fig.add_axes(
                    (
                        (LEFT_IN + k * (each + GAP_IN)) / width,
                        y / height,
                        each / width,
                        r.height_in / height,
                    )
                )
                for k in range(r.panels)
            ]
        )
        y -= BELOW_IN
    for ax in (a for row in out for a in row):
        _fixed_labels(fig, ax)
    return out


def _fixed_labels(fig: Figure, ax: Axes) -> None:
    """The x label :data:`X_LABEL_IN` under the panel, the y label :data:`Y_LABEL_IN` left."""
    from matplotlib.transforms import ScaledTranslation

    inch = fig.dpi_scale_trans
    ax.xaxis.set_label_coords(0.5, 0, ax.transAxes + ScaledTranslation(0, -X_LABEL_IN, inch))
    ax.yaxis.set_label_coords(0, 0.5, ax.transAxes + ScaledTranslation(-Y_LABEL_IN, 0, inch))


def fixed_titles() -> Any:
    """A context in which panels made and titled keep their title just above them (matplotlib
    otherwise measures the tick labels at draw time to move it over any at the top)."""
    import matplotlib

    return matplotlib.rc_context({"axes.titley": 1.0})


def suptitle(fig: Figure, text: str, **kw: object) -> None:
    """The figure's title, centred in the room :func:`figure_height` left above the rows."""
    height = fig.get_size_inches()[1]
    fig.suptitle(text, y=1 - SUPTITLE_PAD_IN / 2 / height, va="top", **kw)  # type: ignore[arg-type]


def figure_bytes(fig: Figure, fmt: str) -> bytes:
    """``fig`` drawn by Agg in format ``fmt`` (``png``, ``jpg``, ``svg``, ``pdf``); a PNG with
    zlib's fastest level (a third of the default's time for ~12 % more bytes on these flat
    pictures)."""
    buf = io.BytesIO()
    extra = {"pil_kwargs": {"compress_level": 1}} if fmt == "png" else {}
    fig.savefig(buf, format=fmt, **extra)  # type: ignore[arg-type]
    return buf.getvalue()
