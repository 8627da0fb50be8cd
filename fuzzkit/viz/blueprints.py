"""Rerun blueprints shipped inside every .rrd, so a recording opens on a layout made for it.

A run recording opens on: per force-controlled axis a column of three plots (measured, true
and set-point force, N; the force error and its change, N; the position correction and its
sum, mm), and the 3-D scene beside them, its camera on the whole arm (joint angles in a second
tab). A surface recording opens on the 3-D surface, seen from between its two inputs, with
its description. The viewer's side panels start folded, so every plot has room for its ticks.
Entity paths are the ones :mod:`fuzzkit.viz.run_series` and :mod:`fuzzkit.viz.surface` log.
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


Vec3 = tuple[float, float, float]


def scene_view(origin: str, name: str, eye: tuple[Vec3, Vec3] | None = None) -> Any:
    """A 3-D view of ``origin`` with the ground grid (the labelled axes are logged data:
    :func:`fuzzkit.viz.recording.log_axes`); ``eye``: the camera's (position, target)."""
    import rerun.blueprint as rrb

    controls = None
    if eye is not None:
        controls = rrb.EyeControls3D(position=eye[0], look_target=eye[1], eye_up=(0.0, 0.0, 1.0))
    return rrb.Spatial3DView(
        origin=origin,
        name=name,
        line_grid=rrb.LineGrid3D(visible=True),
        eye_controls=controls,
    )


def _panels() -> list[Any]:
    """The viewer's side panels folded away: the plots get the height their ticks need."""
    import rerun.blueprint as rrb

    return [
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="collapsed"),
    ]


def run_blueprint(
    controlled_axes: Sequence[str],
    title: str,
    eye: tuple[Vec3, Vec3] | None = None,
    duration_s: float | None = None,
    rules: bool = False,
    adaptive: bool = False,
) -> Any:
    """The layout of a closed-loop run's recording (``controlled_axes``: "x", "z", ...): a
    column per force-controlled axis (force vs set point, error, correction), then the 3-D
    scene seen from ``eye`` (joint angles in a second tab; with ``rules``, a fuzzy-PI run that
    logged its strongest rules under ``control/rules``, two tabs more; with ``adaptive``, a run
    with adaptation, its output gain factor and stiffness estimate in two more). Every plot
    opens on the
    run's whole ``duration_s`` (0 s to the end), so series that start late (e at engagement)
    line up with the forces."""
    import rerun as rr
    import rerun.blueprint as rrb

    span = None
    if duration_s is not None:
        span = rr.TimeRange(
            start=rr.TimeRangeBoundary.absolute(seconds=0.0),
            end=rr.TimeRangeBoundary.absolute(seconds=duration_s),
        )

    def plot(origin: str, name: str) -> Any:
        # the same span on every plot (the viewer's global link ignores a view range)
        axis = rrb.TimeAxis(link="Independent", view_range=span)
        return rrb.TimeSeriesView(origin=origin, name=name, axis_x=axis)

    columns = [
        rrb.Vertical(
            plot(f"{FORCES}/{axis}", f"force {axis} vs set point (N)"),
            plot(f"{ERROR}/{axis}", f"force error e{axis}, de{axis} (N)"),
            plot(f"{CORRECTION}/{axis}", f"position correction du{axis}, u{axis} (mm)"),
        )
        for axis in controlled_axes
    ]
    tabs = [
        scene_view(WORLD, f"3-D scene: {title} (m)", eye),
        plot(JOINTS, "joint angles"),
    ]
    if rules:
        tabs += [
            rrb.TextLogView(origin=RULES, name="strongest fuzzy rules per period"),
            plot(RULES, "strongest rule's strength (0-1)"),
        ]
    if adaptive:
        tabs += [
            plot(f"{ADAPTATION}/gain_scale", "output gain factor"),
            plot(f"{ADAPTATION}/stiffness", "stiffness estimate (N/mm)"),
        ]
    scene = rrb.Tabs(*tabs)
    return rrb.Blueprint(
        rrb.Horizontal(*columns, scene, column_shares=[2] * len(columns) + [3]),
        *_panels(),
    )


#: The surface's camera: its cube ([-1, 1] on every axis) seen from the diagonal between the
#: two inputs' low ends, so neither input is foreshortened more than the other.
SURFACE_EYE: tuple[Vec3, Vec3] = ((-3.4, -3.4, 2.6), (0.0, 0.0, -0.1))


def surface_blueprint(entity: str, title: str) -> Any:
    """The layout of a control-surface recording: the 3-D surface and its description."""
    import rerun.blueprint as rrb

    return rrb.Blueprint(
        rrb.Horizontal(
            scene_view(entity, title, SURFACE_EYE),
            rrb.TextDocumentView(origin=f"{entity}/description", name="about this surface"),
            column_shares=[4, 1],
        ),
        *_panels(),
    )
