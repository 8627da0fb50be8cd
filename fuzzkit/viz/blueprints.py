"""Rerun blueprints shipped inside every .rrd, so a recording opens on a layout made for it.

A run recording opens on: one plot per force-controlled axis (measured, true and set-point
force, N), the force error and its change (N), the position correction and its sum (mm), and
the 3-D scene beside them (joint angles in a second tab). A surface recording opens on the
3-D surface with its description. Entity paths are the ones :mod:`fuzzkit.viz.run_series`
and :mod:`fuzzkit.viz.surface` log.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

#: Where the run series live (see fuzzkit.viz.run_series).
FORCES = "forces"
ERROR = "control/error"
CORRECTION = "control/correction"
ADAPTATION = "adaptation"
RULES = "control/rules"
JOINTS = "joints"
WORLD = "world"


def scene_view(origin: str, name: str) -> Any:
    """A 3-D view of ``origin`` with the ground grid (the labelled axes are logged data:
    :func:`fuzzkit.viz.recording.log_axes`)."""
    import rerun.blueprint as rrb

    return rrb.Spatial3DView(origin=origin, name=name, line_grid=rrb.LineGrid3D(visible=True))


def run_blueprint(
    controlled_axes: Sequence[str], title: str, rules: bool = False, adaptive: bool = False
) -> Any:
    """The layout of a closed-loop run's recording (``controlled_axes``: "x", "z", ...;
    ``rules``: a fuzzy-PI run that logged its strongest rules under ``control/rules``;
    ``adaptive``: a run with adaptation, whose gain factor and stiffness estimate it plots)."""
    import rerun.blueprint as rrb

    force_views = [
        rrb.TimeSeriesView(origin=f"{FORCES}/{axis}", name=f"force {axis} vs set point (N)")
        for axis in controlled_axes
    ]
    control_views = [
        rrb.TimeSeriesView(origin=ERROR, name="force error e, de (N)"),
        rrb.TimeSeriesView(origin=CORRECTION, name="position correction du, u (mm)"),
    ]
    if adaptive:
        control_views += [
            rrb.TimeSeriesView(origin=f"{ADAPTATION}/gain_scale", name="output gain factor"),
            rrb.TimeSeriesView(origin=f"{ADAPTATION}/stiffness", name="stiffness estimate (N/mm)"),
        ]
    tabs = [
        scene_view(WORLD, f"3-D scene: {title} (m)"),
        rrb.TimeSeriesView(origin=JOINTS, name="joint angles"),
    ]
    if rules:
        tabs += [
            rrb.TextLogView(origin=RULES, name="strongest fuzzy rules per period"),
            rrb.TimeSeriesView(origin=RULES, name="strongest rule's strength (0-1)"),
        ]
    scene = rrb.Tabs(*tabs)
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(*force_views, *control_views),
            scene,
            column_shares=[3, 2],
        ),
        collapse_panels=False,
    )


def surface_blueprint(entity: str, title: str) -> Any:
    """The layout of a control-surface recording: the 3-D surface and its description."""
    import rerun.blueprint as rrb

    return rrb.Blueprint(
        rrb.Horizontal(
            scene_view(entity, title),
            rrb.TextDocumentView(origin=f"{entity}/description", name="about this surface"),
            column_shares=[4, 1],
        ),
        collapse_panels=True,
    )
