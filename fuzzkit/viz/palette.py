"""One look for every figure of a study: a colour per controller, a line style per gains set.

The report's force figures, the stiffness study, the latency map, the sweep summary and the
documentation figures all draw PI and fuzzy-PI in the same colour, so a reader who learnt
"orange is PI" in one figure can trust it in the next. Gains sets are told apart by the line
(the default a wide pale band under the others), and a run that tripped the safety limit by
one marker, never by a plotted overshoot.
"""

from __future__ import annotations

from typing import Any

#: The colour of each controller, in every figure.
CONTROLLER_COLOURS = {"pi": "tab:orange", "fuzzy-pi": "tab:blue"}
#: Colours of other controllers (controller specs), in the order they appear; none is red,
#: which marks trips.
OTHER_COLOURS = ("tab:green", "tab:purple", "tab:brown", "tab:olive", "tab:cyan")
CONTROLLER_NAMES = {"pi": "PI", "fuzzy-pi": "fuzzy-PI"}

#: How each gains set is drawn (line style, width, alpha, zorder): the default as a wide pale
#: band under the others, so both stay visible where they coincide.
GAINS_STYLE: dict[str, tuple[str, float, float, int]] = {
    "default": ("-", 3.2, 0.4, 2),
    "matched": ("--", 1.5, 0.9, 3),
    "tuned": ("-", 1.1, 1.0, 3),
}
OTHER_GAINS_STYLE = (":", 1.2, 1.0, 3)
SETPOINT_STYLE: dict[str, Any] = {"color": "black", "ls": "--", "lw": 0.9, "zorder": 4}
#: Where a run tripped the safety limit (and stopped): a red cross, in every figure.
TRIP_STYLE: dict[str, Any] = {
    "marker": "X",
    "ms": 9,
    "mfc": "tab:red",
    "mec": "black",
    "mew": 0.8,
    "ls": "none",
    "zorder": 6,
}
TRIP_LABEL = "tripped (safety limit)"


def controller_colour(ctrl: str, order: tuple[str, ...] = ()) -> str:
    """The colour of controller ``ctrl``; others by their place in ``order`` (same call, same
    colour)."""
    if ctrl in CONTROLLER_COLOURS:
        return CONTROLLER_COLOURS[ctrl]
    others = [c for c in order if c not in CONTROLLER_COLOURS]
    index = others.index(ctrl) if ctrl in others else 0
    return OTHER_COLOURS[index % len(OTHER_COLOURS)]


def controller_name(ctrl: str) -> str:
    """``PI``, ``fuzzy-PI``, or the name as given."""
    return CONTROLLER_NAMES.get(ctrl, ctrl)


def gains_style(label: str) -> dict[str, Any]:
    """Line keyword arguments (no colour) of gains set ``label``."""
    ls, lw, alpha, z = GAINS_STYLE.get(label, OTHER_GAINS_STYLE)
    return {"ls": ls, "lw": lw, "alpha": alpha, "zorder": z}


def gains_legend(labels: list[str], trips: bool) -> tuple[list[Any], list[str]]:
    """Legend entries (in grey: the colour says the controller) for ``labels``, the set point
    and, when ``trips``, the trip marker."""
    from matplotlib.lines import Line2D

    handles: list[Any] = [Line2D([], [], color="0.3", **gains_style(g)) for g in labels]
    names = [f"{g} gains" for g in labels]
    handles.append(Line2D([], [], **SETPOINT_STYLE))
    names.append("set point")
    if trips:
        handles.append(Line2D([], [], **TRIP_STYLE))
        names.append(TRIP_LABEL)
    return handles, names
