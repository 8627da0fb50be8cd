"""Control surfaces of two-input rule bases: the grid, a Rerun 3-D mesh and a PNG.

The surface ``z = F(x, y)`` is computed with the exact engine over the two input ranges; the
label-peak grid (every pair of term peaks, where a table-driven controller is "anchored") is
logged alongside as points so a viewer shows which rule cell dominates where.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import ConfigError, EvaluationError
from fuzzkit.fileio import write_atomic
from fuzzkit.fuzzy.model import RuleBase, Term, Variable
from fuzzkit.viz.recording import open_recording

FloatArray = npt.NDArray[np.float64]

#: Grids larger than this are refused: 1001 x 1001 already takes the engine seconds.
MAX_RESOLUTION = 1001


def _check_shape(rb: RuleBase, output: str | None) -> str:
    if len(rb.inputs) != 2:
        raise EvaluationError(
            f"a control surface needs a rule base with exactly 2 inputs; {rb.name!r} has "
            f"{len(rb.inputs)} ({', '.join(rb.input_names)})"
        )
    if output is None:
        return rb.outputs[0].name
    if output not in rb.output_names:
        raise EvaluationError(
            f"unknown output {output!r} for the surface; expected one of "
            f"{', '.join(rb.output_names)}"
        )
    return output


def surface_grid(
    rb: RuleBase, resolution: int = 101, output: str | None = None
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The control surface of a 2-input rule base on a ``resolution`` x ``resolution`` grid.

    Parameters
    ----------
    rb
        A rule base with exactly two inputs.
    resolution
        Grid points per input, spanning each input's range end to end (2 .. 1001).
    output
        Which output to compute (default: the first).

    Returns
    -------
    x, y, z
        ``x`` (the first input) and ``y`` (the second) as 1-D grids, and ``z[i, j] =
        F(x[i], y[j])``.

    Raises
    ------
    EvaluationError
        If the rule base does not have two inputs or ``output`` is unknown.
    ConfigError
        If ``resolution`` is outside 2 .. 1001.
    """
    from fuzzkit.fuzzy.inference import Engine

    name = _check_shape(rb, output)
    if not 2 <= resolution <= MAX_RESOLUTION:
        raise ConfigError(f"resolution must be between 2 and {MAX_RESOLUTION}, got {resolution}")
    vx, vy = rb.inputs
    x = np.linspace(vx.low, vx.high, resolution)
    y = np.linspace(vy.low, vy.high, resolution)
    xx, yy = np.meshgrid(x, y, indexing="ij")
    z = Engine(rb).evaluate({vx.name: xx, vy.name: yy})[name]
    return x, y, np.asarray(z, dtype=np.float64)


def term_peak(term: Term, var: Variable) -> float:
    """Where a term is most typical: its peak (or plateau middle), clipped to the range."""
    # the weighted-average centre is exactly this point, for every shape
    from fuzzkit.fuzzy.membership import centre

    peak = centre(term, var.low, var.high)
    return float(min(max(peak, var.low), var.high))


def peak_grid(rb: RuleBase, output: str | None = None) -> tuple[FloatArray, list[str]]:
    """The surface at every pair of input term peaks: ``(N, 3)`` points and their labels."""
    from fuzzkit.fuzzy.inference import Engine

    name = _check_shape(rb, output)
    vx, vy = rb.inputs
    px = [(t.name, term_peak(t, vx)) for t in vx.terms]
    py = [(t.name, term_peak(t, vy)) for t in vy.terms]
    xs = np.array([[a for _, a in px]] * len(py)).T.ravel()
    ys = np.array([[b for _, b in py]] * len(px)).ravel()
    z = Engine(rb).evaluate({vx.name: xs, vy.name: ys})[name]
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

    from fuzzkit.viz.recording import log_axes

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
    # Each axis's ticks run along a different edge of the cube, just outside it, so that no
    # two axes' end ticks share a corner.
    edges = ([0.0, -1.15, -1.0], [1.15, 0.0, -1.0], [-1.0, 1.15, 0.0])
    for axis, var in enumerate((vx, vy, out)):
        raw = var.low + (u + 1.0) * 0.5 * (var.high - var.low)
        for t, r in zip(u, raw, strict=True):
            p = list(edges[axis])
            p[axis] = float(t)
            points.append((p[0], p[1], p[2]))
            labels.append(f"{var.name}={r:.4g}")
    rec.log(
        f"{entity}/ticks",
        rr.Points3D(points, radii=[0.012], colors=[(200, 200, 200)], labels=labels),
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
            rr.Points3D(peaks_unit, radii=0.03, labels=labels, colors=[(235, 235, 235)]),
            static=True,
        )
        _log_labelled_axes(rec, entity, rb, out)
    return Path(path)


def write_surface_png(
    rb: RuleBase,
    path: str | os.PathLike[str],
    resolution: int = 101,
    output: str | None = None,
) -> Path:
    """Render the control surface as a 3-D plot to a PNG (matplotlib, Agg), atomically."""
    import io

    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    name = _check_shape(rb, output)
    x, y, z = surface_grid(rb, resolution, name)
    xx, yy = np.meshgrid(x, y, indexing="ij")
    fig = Figure(figsize=(7, 5.5), dpi=100)
    ax = fig.add_subplot(projection="3d")
    ax.plot_surface(xx, yy, z, cmap="coolwarm", linewidth=0, antialiased=True)
    vx, vy = rb.inputs
    ax.set_xlabel(vx.name)
    ax.set_ylabel(vy.name)
    ax.set_zlabel(name)
    ax.set_title(f"{rb.name}: {name} = F({vx.name}, {vy.name})")
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return write_atomic(path, buf.getvalue())
