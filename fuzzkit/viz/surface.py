"""Control surfaces: the grid, a Rerun 3-D mesh and a matplotlib figure (PNG or SVG).

The surface ``z = F(x, y)`` is computed with the exact engine over two input ranges (any two
inputs of the rule base; the others are held at fixed values, as MATLAB's ``gensurf`` does); the
label-peak grid (every pair of term peaks, where a table-driven controller is "anchored") is
logged alongside as points so a viewer shows which rule cell dominates where.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import ConfigError, EvaluationError, did_you_mean
from fuzzkit.fuzzy.describe import axis_label, num
from fuzzkit.fuzzy.model import RuleBase, Term, Variable
from fuzzkit.viz.figures import figure_format, new_figure, save_figure
from fuzzkit.viz.recording import open_recording

FloatArray = npt.NDArray[np.float64]

#: Grids larger than this are refused: 1001 x 1001 already takes the engine seconds.
MAX_RESOLUTION = 1001


@dataclass(frozen=True)
class SurfaceAxes:
    """Which two inputs a surface spans and where every other input is held.

    ``fixed`` maps each other input to its value (given with ``--fix`` / ``fixed=``, else the
    middle of its range, as MATLAB's ``gensurf`` does); ``output`` is the output drawn.
    """

    x: Variable
    y: Variable
    fixed: dict[str, float]
    output: str

    def point(self, xs: FloatArray, ys: FloatArray) -> dict[str, FloatArray]:
        """Engine inputs for the points ``(xs, ys)``, the fixed inputs broadcast."""
        full = {name: np.full(np.shape(xs), v) for name, v in self.fixed.items()}
        return {self.x.name: xs, self.y.name: ys, **full}

    def fixed_text(self, rb: RuleBase) -> str:
        """``r = 0.5`` (every held input) for the title; empty for a 2-input rule base."""
        return ", ".join(
            f"{name} = {num(v)}{_units(rb.input(name))}" for name, v in self.fixed.items()
        )


def _units(var: Variable) -> str:
    return f" {var.units}" if var.units else ""


def surface_axes(
    rb: RuleBase,
    output: str | None = None,
    inputs: Sequence[str] | None = None,
    fixed: Mapping[str, float] | None = None,
) -> SurfaceAxes:
    """Check and resolve the choice of surface axes (see :class:`SurfaceAxes`).

    ``inputs`` names the two inputs to span (default: the first two); ``fixed`` gives values
    for other inputs (default: the middle of their ranges).

    Raises
    ------
    EvaluationError
        Naming what is wrong: fewer than 2 inputs, an unknown or repeated input, a fixed value
        for a spanned input, or a fixed value that is not finite or outside the input's range;
        or an unknown output.
    """
    if len(rb.inputs) < 2:
        raise EvaluationError(
            f"a control surface needs a rule base with at least 2 inputs; {rb.name!r} has "
            f"{len(rb.inputs)} ({', '.join(rb.input_names)})"
        )
    names = list(rb.input_names)
    if output is None:
        output = rb.outputs[0].name
    elif output not in rb.output_names:
        raise EvaluationError(
            f"unknown output {output!r} for the surface{did_you_mean(output, rb.output_names)}; "
            f"expected one of {', '.join(rb.output_names)}"
        )
    if inputs is None:
        chosen = names[:2]
    else:
        chosen = list(inputs)
        if len(chosen) != 2:
            raise EvaluationError(
                f"a surface spans exactly 2 inputs, got {len(chosen)} ({', '.join(chosen)}); "
                f"choose two of {', '.join(names)}"
            )
        for name in chosen:
            if name not in names:
                raise EvaluationError(
                    f"unknown input {name!r} for the surface{did_you_mean(name, names)}; "
                    f"expected two of {', '.join(names)}"
                )
        if chosen[0] == chosen[1]:
            raise EvaluationError(
                f"the surface needs two different inputs, got {chosen[0]!r} twice"
            )
    given = dict(fixed or {})
    for name, value in given.items():
        if name not in names:
            raise EvaluationError(
                f"cannot fix unknown input {name!r}{did_you_mean(name, names)}; "
                f"inputs are {', '.join(names)}"
            )
        if name in chosen:
            raise EvaluationError(
                f"cannot fix {name!r}: it is one of the surface's two axes "
                f"({chosen[0]}, {chosen[1]}); fix only the other inputs"
            )
        var = rb.input(name)
        if not math.isfinite(value) or not var.low <= value <= var.high:
            raise EvaluationError(
                f"fixed value of {name!r} must be a finite number inside its range "
                f"[{num(var.low)}, {num(var.high)}], got {num(value)}"
            )
    held = {
        v.name: float(given.get(v.name, 0.5 * (v.low + v.high)))
        for v in rb.inputs
        if v.name not in chosen
    }
    return SurfaceAxes(rb.input(chosen[0]), rb.input(chosen[1]), held, output)


def surface_grid(
    rb: RuleBase,
    resolution: int = 101,
    output: str | None = None,
    inputs: Sequence[str] | None = None,
    fixed: Mapping[str, float] | None = None,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The control surface of a rule base on a ``resolution`` x ``resolution`` grid.

    Parameters
    ----------
    rb
        A rule base with at least two inputs.
    resolution
        Grid points per input, spanning each input's range end to end (2 .. 1001).
    output
        Which output to compute (default: the first).
    inputs
        The two inputs to span (default: the first two).
    fixed
        Values of the other inputs (default: the middle of each one's range).

    Returns
    -------
    x, y, z
        ``x`` (the first spanned input) and ``y`` (the second) as 1-D grids, and ``z[i, j] =
        F(x[i], y[j])``.

    Raises
    ------
    EvaluationError
        See :func:`surface_axes`.
    ConfigError
        If ``resolution`` is outside 2 .. 1001.
    """
    from fuzzkit.fuzzy.inference import Engine

    axes = surface_axes(rb, output, inputs, fixed)
    if not 2 <= resolution <= MAX_RESOLUTION:
        raise ConfigError(f"resolution must be between 2 and {MAX_RESOLUTION}, got {resolution}")
    x = np.linspace(axes.x.low, axes.x.high, resolution)
    y = np.linspace(axes.y.low, axes.y.high, resolution)
    xx, yy = np.meshgrid(x, y, indexing="ij")
    z = Engine(rb).evaluate(axes.point(xx, yy))[axes.output]
    return x, y, np.asarray(z, dtype=np.float64)


def _check_shape(rb: RuleBase, output: str | None) -> str:
    """The output of a 2-input rule base's recording (it spans both inputs; no fixing)."""
    if len(rb.inputs) != 2:
        raise EvaluationError(
            f"a surface recording needs a rule base with exactly 2 inputs; {rb.name!r} has "
            f"{len(rb.inputs)} ({', '.join(rb.input_names)}); use the PNG, which can fix inputs"
        )
    return surface_axes(rb, output).output


def term_peak(term: Term, var: Variable) -> float:
    """Where a term is most typical: its peak (or plateau middle), clipped to the range."""
    # the weighted-average centre is exactly this point, for every shape
    from fuzzkit.fuzzy.membership import centre

    peak = centre(term, var.low, var.high)
    return float(min(max(peak, var.low), var.high))


def peak_grid(
    rb: RuleBase,
    output: str | None = None,
    inputs: Sequence[str] | None = None,
    fixed: Mapping[str, float] | None = None,
) -> tuple[FloatArray, list[str]]:
    """The surface at every pair of input term peaks: ``(N, 3)`` points and their labels."""
    from fuzzkit.fuzzy.inference import Engine

    axes = surface_axes(rb, output, inputs, fixed)
    vx, vy = axes.x, axes.y
    px = [(t.name, term_peak(t, vx)) for t in vx.terms]
    py = [(t.name, term_peak(t, vy)) for t in vy.terms]
    xs = np.array([[a for _, a in px]] * len(py)).T.ravel()
    ys = np.array([[b for _, b in py]] * len(px)).ravel()
    z = Engine(rb).evaluate(axes.point(xs, ys))[axes.output]
    labels = [f"{vx.name}={a}, {vy.name}={b}" for a, _ in px for b, _ in py]
    return np.column_stack([xs, ys, np.asarray(z, dtype=np.float64)]), labels


def _colours(z: FloatArray, low: float, high: float) -> npt.NDArray[np.uint8]:
    """Blue (low) to red (high) vertex colours; NaN is grey."""
    import matplotlib

    t = np.clip((z - low) / (high - low), 0.0, 1.0)
    rgba = matplotlib.colormaps["coolwarm"](np.nan_to_num(t, nan=0.5))
    rgba[np.isnan(z)] = (0.5, 0.5, 0.5, 1.0)
    return np.asarray(np.round(rgba * 255), dtype=np.uint8)


def _mesh(x: FloatArray, y: FloatArray, z: FloatArray) -> tuple[FloatArray, npt.NDArray[np.uint32]]:
    nx, ny = len(x), len(y)
    xx, yy = np.meshgrid(x, y, indexing="ij")
    vertices = np.column_stack([xx.ravel(), yy.ravel(), np.nan_to_num(z).ravel()])
    idx = np.arange(nx * ny, dtype=np.uint32).reshape(nx, ny)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    triangles = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    return vertices, triangles


def _to_unit(values: FloatArray, var: Variable) -> FloatArray:
    """``values`` of ``var`` mapped linearly from its range onto [-1, 1]."""
    return np.asarray(2.0 * (values - var.low) / (var.high - var.low) - 1.0, dtype=np.float64)


def _axis_title(var: Variable, role: str) -> str:
    units = getattr(var, "units", None)  # optional on Variable (rule bases may carry units)
    return f"{var.name}{f' ({units})' if units else ''} [{role}]"


def _log_labelled_axes(rec: Any, entity: str, rb: RuleBase, out: Variable, ticks: int = 5) -> None:
    """Axis arrows and tick marks for the normalised cube, labelled with raw values."""
    import rerun as rr

    from fuzzkit.viz.recording import AXIS_ARROW_COLOURS, log_axes

    vx, vy = rb.inputs
    corner = (-1.0, -1.0, -1.0)
    log_axes(
        rec,
        f"{entity}/axes",
        (
            _axis_title(vx, "input 1"),
            _axis_title(vy, "input 2"),
            _axis_title(out, "output"),
        ),
        2.5,
        corner,
    )
    u = np.linspace(-1.0, 1.0, ticks)
    points: list[tuple[float, float, float]] = []
    labels: list[str] = []
    colours: list[tuple[int, int, int]] = []
    # The inputs' ticks run beside their arrows (the edges nearest the default camera,
    # :data:`fuzzkit.viz.blueprints.SURFACE_EYE`), the output's up the back corner, far enough
    # out that its lowest tick stays clear of the second input's highest.
    edges = ([0.0, -1.15, -1.0], [-1.15, 0.0, -1.0], [-1.0, 1.45, 0.0])
    for axis, var in enumerate((vx, vy, out)):
        raw = var.low + (u + 1.0) * 0.5 * (var.high - var.low)
        for t, r in zip(u, raw, strict=True):
            p = list(edges[axis])
            p[axis] = float(t)
            points.append((p[0], p[1], p[2]))
            labels.append(f"{var.name}={r:.4g}")
            colours.append(AXIS_ARROW_COLOURS[axis])
    # Each tick in its axis's colour (the arrows'): readable on the dark theme and the light
    # one, and it says which axis a tick belongs to.
    rec.log(
        f"{entity}/ticks",
        rr.Points3D(points, radii=[0.02], colors=colours, labels=labels, show_labels=True),
        static=True,
    )


def write_surface_rrd(
    rb: RuleBase,
    path: str | os.PathLike[str],
    resolution: int = 101,
    output: str | None = None,
) -> Path:
    """Write the control surface to a Rerun recording (``.rrd``), atomically.

    The surface is drawn in normalised coordinates: every input and the output are mapped
    linearly from their ranges onto [-1, 1], so a rule base with e in [-20, 20], de in
    [-2, 2] and an output of 0-100 % is a readable cube, not a sliver; the axes are labelled
    with the variables' names and the tick marks with raw values.

    Entities: ``surface/<output>`` (a ``Mesh3D`` with blue-to-red vertex colours),
    ``surface/<output>/label_peaks`` (``Points3D`` at every pair of input term peaks, labelled),
    ``surface/<output>/axes`` and ``/ticks`` (labelled axes and raw-value ticks) and
    ``surface/<output>/description`` (a text document naming the rule base, axes and ranges).
    The file carries a blueprint (``fuzzkit.viz.blueprints``) opening on the surface.
    """
    import rerun as rr

    from fuzzkit.viz.blueprints import surface_blueprint

    name = _check_shape(rb, output)
    x, y, z = surface_grid(rb, resolution, name)
    out = rb.output(name)
    vx, vy = rb.inputs
    vertices, triangles = _mesh(_to_unit(x, vx), _to_unit(y, vy), _to_unit(z, out))
    peaks, labels = peak_grid(rb, name)
    peaks_unit = np.column_stack(
        [_to_unit(peaks[:, 0], vx), _to_unit(peaks[:, 1], vy), _to_unit(peaks[:, 2], out)]
    )
    entity = f"surface/{name}"
    title = f"{rb.name}: {name} = F({vx.name}, {vy.name})"

    with open_recording(
        path,
        "fuzzkit",
        f"surface-{rb.name}-{name}",
        blueprint=surface_blueprint(entity, title),
        send_properties=False,
    ) as rec:
        rec.log(
            f"{entity}/description",
            rr.TextDocument(
                f"Control surface of {rb.name}: {name} = F({vx.name}, {vy.name}), "
                f"{resolution} x {resolution} grid, exact engine.\n\n"
                "Drawn in normalised coordinates: each axis maps its variable's range onto "
                f"[-1, 1]: {vx.name} [{vx.low:g}, {vx.high:g}] (x), "
                f"{vy.name} [{vy.low:g}, {vy.high:g}] (y), "
                f"{name} [{out.low:g}, {out.high:g}] (z). Tick labels give raw values.",
            ),
            static=True,
        )
        rec.log(entity, rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        rec.log(
            entity,
            rr.Mesh3D(
                vertex_positions=vertices,
                triangle_indices=triangles,
                vertex_colors=_colours(z.ravel(), out.low, out.high),
            ),
            static=True,
        )
        rec.log(
            f"{entity}/label_peaks",
            rr.Points3D(peaks_unit, radii=0.03, labels=labels, colors=[(250, 190, 30)]),
            static=True,
        )
        _log_labelled_axes(rec, entity, rb, out)
    return Path(path)


def surface_figure(
    rb: RuleBase,
    resolution: int = 101,
    output: str | None = None,
    inputs: Sequence[str] | None = None,
    fixed: Mapping[str, float] | None = None,
) -> Any:
    """The control surface as a 3-D matplotlib Figure with a colour bar (no pyplot, no backend).

    Axes are labelled with the variables' units; other inputs are held as in
    :func:`surface_axes` and named in the title. Arguments as for :func:`surface_grid`.

    Examples
    --------
    >>> fig = surface_figure(fuzzkit.load("three_input"), inputs=("e", "r"), fixed={"de": 0.2})
    ... # doctest: +SKIP
    """
    from matplotlib.ticker import MaxNLocator

    axes = surface_axes(rb, output, inputs, fixed)
    x, y, z = surface_grid(rb, resolution, axes.output, (axes.x.name, axes.y.name), axes.fixed)
    out = rb.output(axes.output)
    xx, yy = np.meshgrid(x, y, indexing="ij")
    fig = new_figure(7.6, 5.6)
    ax = fig.add_subplot(projection="3d")
    surf = ax.plot_surface(
        xx, yy, z, cmap="coolwarm", vmin=out.low, vmax=out.high, linewidth=0, antialiased=True
    )
    ax.set_zlim(out.low, out.high)
    # Few ticks, and the labels pushed out: the default crowds the y ticks into its label.
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_major_locator(MaxNLocator(5))
    ax.tick_params(labelsize=8, pad=1)
    ax.set_xlabel(axis_label(axes.x), labelpad=8)
    ax.set_ylabel(axis_label(axes.y), labelpad=8)
    ax.set_zlabel(axis_label(out), labelpad=6)
    ax.view_init(elev=28, azim=-128)
    ax.set_box_aspect(None, zoom=0.88)  # room for the z label, which sits outside the box
    bar = fig.colorbar(surf, ax=ax, shrink=0.62, pad=0.04)
    bar.set_label(axis_label(out))
    held = axes.fixed_text(rb)
    title = f"{rb.name}: {axes.output} = F({axes.x.name}, {axes.y.name})"
    fig.suptitle(title + (f"\nat {held}" if held else ""), fontsize=11)
    fig.subplots_adjust(left=0.02, right=0.95, bottom=0.04, top=0.9 if held else 0.93)
    return fig


def write_surface_png(
    rb: RuleBase,
    path: str | os.PathLike[str],
    resolution: int = 101,
    output: str | None = None,
    inputs: Sequence[str] | None = None,
    fixed: Mapping[str, float] | None = None,
) -> Path:
    """Write :func:`surface_figure` to ``path`` (.png or .svg by suffix), atomically."""
    figure_format(path, "surface file")
    return save_figure(surface_figure(rb, resolution, output, inputs, fixed), path)
