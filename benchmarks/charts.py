"""Charts of a saved benchmark run (matplotlib, PNG).

Drawn from the raw results only (:func:`benchmarks.suite.load`):

``accuracy_speed.png``
    For each query type, queries per second against the worst and median
    error, in ``eps * S`` (every answered query) and relative to the exact
    distance ``d*`` (the queries with ``d* > 0``), one marker per method or
    backend, with the Pareto front of those that answered every query.
    Errors of 0 (and below the axis' floor) are drawn on the floor, which
    is labelled.
``stability_triangle.png``, ``stability_round.png``
    Each sweep of :mod:`proximity.testing.scenes`: the worst error against the
    swept difficulty, one line per method or backend, over a strip that
    shows the share of queries with no answer, so that failures are seen
    where they begin.
``stability_pairs.png``
    The same for the primitive pairs (segment-segment, segment-triangle,
    triangle-triangle), from :mod:`benchmarks.pair_stability`'s own raw
    data: one row per sweep, one column per pair.
``tessellation.png``
    For backends that cut circles and disks into ``K`` segments: error and
    time per query against ``K``, with the sagitta bound and proximity's
    ``robust`` for comparison.
``mesh_peers.png``
    From the mesh benchmark's comparison with other libraries
    (:func:`benchmarks.meshes.run_peers`, its own raw data): for each mesh
    and point set, points per second on one thread against the largest
    error, relative to the mesh's size, one marker per library.

Every chart has a title, labelled axes with units, and a caption
(:data:`CAPTIONS`, also printed under it in the report) saying what to look at.
"""

import io
import math
from pathlib import Path

import numpy as np

from benchmarks import summary

#: Colours and markers that stay the same for an entity in every chart.
STYLE = {
    "eberly": ("tab:orange", "s"),
    "robust": ("tab:blue", "o"),
    "certified": ("tab:green", "D"),
    "fcl": ("tab:red", "^"),
    "trimesh": ("tab:purple", "v"),
    "trimesh[raw]": ("tab:pink", "<"),
    "pybullet": ("tab:brown", ">"),
    "coal": ("tab:olive", "P"),
    "numpy": ("tab:gray", "X"),
}
_SPARE = [("tab:cyan", "*"), ("black", "h"), ("tab:pink", "d")]

#: Smallest error drawn in eps*S: an exact answer (error 0) is drawn here.
FLOOR = 1e-2

#: The same for each unit of the accuracy chart: a relative error of 1e-18 is
#: far below a double's resolution, 2.2e-16.
FLOORS = {"error_eps_s": FLOOR, "error_relative": 1e-18}

#: Top of the error axes; above this, errors are written out.
CAP = {"error_eps_s": 10.0**307.5, "error_relative": 1e30}

#: robust's bound, drawn for reference, in eps*S.
BOUND = 8.0

#: certified's bound, relative to d*: one ulp of d* is at most 2^-52 of it.
RELATIVE_BOUND = 2.0**-52

#: The reference line of each unit, and its label.
BOUNDS = {
    "error_eps_s": (BOUND, "8 eps·S: robust's bound"),
    "error_relative": (RELATIVE_BOUND, "2.2e-16 (one ulp): certified's bound"),
}

#: Axis labels of each sweep's difficulty.
DIFFICULTY = {
    "near_surface": "distance from the triangle / its size",
    "sliver": "sliver height / longest edge",
    "needle": "short edge / long edges",
    "small": "triangle size",
    "offset": "offset from the origin (triangle size 1e-3)",
    "far_points": "distance / triangle size",
    "magnitude": "coordinate magnitude",
    "degenerate": "zero-area triangle",
    "on_feature": "the point is exactly on",
    "disk_axis": "distance from the axis / R",
    "disk_rim": "distance from the rim / R",
    "disk_offset": "offset from the origin (R ~ 1e-3)",
    "pair_contact": "gap (size ~1; negative: crossing)",
    "pair_near_parallel": "angle between the features (rad)",
    "pair_parallel": "exactly parallel features",
    "pair_degenerate": "zero-length segment or zero-area triangle",
    "pair_offset": "offset from the origin (size 1e-3)",
    "pair_far": "distance / size",
    "pair_magnitude": "coordinate magnitude",
}

DPI = 100

_STABILITY_CAPTION = (
    "What to look at: where a line rises above the dashed line (robust's bound, 8 eps·S) and "
    "where its failure share (upper strip) leaves 0, as each sweep gets harder to the right."
)

#: One line under each chart: what to look at.
CAPTIONS = {
    "accuracy_speed": (
        "What to look at: markers low and to the right are accurate and fast (filled: worst, hollow: "
        "median). Top row: error in eps·S (eps = 2.2e-16, S the query's size), the unit of robust's "
        "bound, over every answered query. Bottom row: error relative to the exact distance d*, where "
        "d* > 0; certified stays within one ulp of d*. robust's bound is on the size: for a point a "
        "hair's breadth from the shape its relative error can be large while its error is a few eps·S."
    ),
    "stability_triangle": _STABILITY_CAPTION,
    "stability_round": _STABILITY_CAPTION,
    "stability_pairs": (
        "What to look at: where a line rises above the dashed line (robust's pair bound, 16 eps·S) and where "
        "its failure share (upper strip: no answer, or junk witness points) leaves 0. python-fcl and coal: "
        "segments as capsules of radius 0, triangles as one-triangle hierarchies; numpy: the textbook "
        "segment formula."
    ),
    "tessellation": (
        "What to look at: the gap between the libraries' lines and proximity's flat blue lines; "
        "the libraries' error follows the sagitta and shrinks only as K, and with it their time, grows."
    ),
    "mesh_peers": (
        "What to look at: markers low and to the right are accurate and fast. Every library on one "
        "thread, on the same points; the error is the largest against the exact distance, over the "
        "first points of each set, as a fraction of the mesh's size. A red count: points answered with "
        "a face that is not the nearest (or no answer), over every point timed."
    ),
}

#: Colours and markers of the mesh benchmark's libraries.
PEER_STYLE = {
    "proximity": ("tab:blue", "o"),
    "open3d": ("tab:green", "s"),
    "libigl": ("tab:orange", "D"),
    "warp": ("tab:purple", "v"),
    "fcpw": ("tab:cyan", "*"),
    "meshlib": ("tab:gray", "h"),
    "coal": ("tab:brown", "P"),
    "fcl": ("tab:red", "^"),
    "pcu": ("tab:olive", "X"),
    "trimesh": ("tab:pink", "<"),
}


_EXTRA = {}


def style(name):
    """``(colour, marker)`` of an entity; others (a method added later) get spare styles in turn."""
    if name in STYLE:
        return STYLE[name]
    return _EXTRA.setdefault(name, _SPARE[len(_EXTRA) % len(_SPARE)])


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.rcParams.update({"font.size": 9, "axes.titlesize": 10, "legend.fontsize": 9})
    return plt


def _floor(values):
    return np.maximum(np.asarray(values, dtype=np.float64), FLOOR)


def _save(fig, path):
    """Write a PNG with a palette of 256 colours: a third of the size, for the same look."""
    import matplotlib.pyplot as plt
    from PIL import Image

    buffer = io.BytesIO()
    fig.savefig(buffer, dpi=DPI, format="png")
    plt.close(fig)
    buffer.seek(0)
    with Image.open(buffer) as image:
        image.convert("RGB").quantize(colors=256).save(path, optimize=True)
    return path


def _subtitle(raw):
    meta = raw["meta"]
    cfg = meta["config"]
    return (
        f"{meta['command']}  ·  seed {cfg['seed']}  ·  {cfg['n_accuracy']} queries per family  ·  "
        f"{meta['machine']['cpu']}, {meta['machine']['cores']} cores  ·  {meta['date'][:10]}"
    )


def _caption(fig, name, y=0.012):
    """The chart's caption (:data:`CAPTIONS`) along the bottom of the figure, wrapped to its width."""
    import textwrap

    width = int(fig.get_figwidth() * DPI / 7.4)
    fig.text(
        0.5, y, textwrap.fill(CAPTIONS[name], width), ha="center", va="bottom", fontsize=9, style="italic"
    )


# -- 1. accuracy against speed ---------------------------------------------------------


def accuracy_speed(raw, path):
    """Queries per second against worst and median error, per query type.

    The top row is in ``eps * S`` over every answered query; the bottom row in
    ulps of ``d*`` over those with ``d* > 0`` (see :mod:`benchmarks.summary`).
    """
    plt = _plt()
    units = list(summary.SHOWN)
    fig, axes = plt.subplots(len(units), 3, figsize=(13, 9.2), squeeze=False)
    seen = {}
    for col, kind in enumerate(summary.KINDS):
        stats = summary.by_kind(raw, kind)
        for row, unit in enumerate(units):
            ax = axes[row, col]
            handles, note = _speed_panel(ax, stats, unit, failures=row == 0)
            seen.update(handles)
            on_shape = max((s.on_shape for s in stats.values()), default=0)
            lines = [f"point–{kind}"] if row == 0 else []
            if unit != "error_eps_s" and on_shape:
                lines.append(f"{on_shape} queries with d* = 0 left out (they are in the row above)")
            if note:
                lines.append(note)
            ax.set_title("\n".join(lines), fontsize=10 if row == 0 else 8)
            if row == len(units) - 1:
                ax.set_xlabel("queries per second (median over families)")
            if col == 0:
                ax.set_ylabel(f"error ({summary.UNITS[unit]})")
    from matplotlib.lines import Line2D

    handles = list(seen.values()) + [
        Line2D([], [], marker="o", color="gray", ls="", markeredgecolor="black"),
        Line2D([], [], marker="o", color="gray", ls="", markerfacecolor="white"),
        Line2D([], [], color="black", ls="--"),
    ]
    labels = list(seen) + [
        "filled: worst",
        "hollow: median",
        "Pareto front of the worst error\n(shaded: dominated)",
    ]
    fig.legend(
        handles,
        labels,
        loc="lower center",
        ncol=min(len(labels), 6),
        frameon=False,
        bbox_to_anchor=(0.5, 0.07),
    )
    fig.suptitle("Accuracy against speed: errors over the answered queries of every scene family", y=0.995)
    fig.text(
        0.5,
        0.955,
        _subtitle(raw) + "  ·  errors of 0 drawn on the labelled floor of each axis",
        ha="center",
        fontsize=8,
        color="dimgray",
    )
    _caption(fig, "accuracy_speed")
    fig.tight_layout(rect=(0, 0.15, 1, 0.95))
    return _save(fig, path)


def _speed_panel(ax, stats, unit, failures):
    """One query type and unit: a worst and a median marker per entity.

    Returns the legend handles and a note for the panel's title (empty
    unless some error is beyond the top of the axis).

    Errors beyond the top of the axis are drawn on its edge with their value;
    with ``failures``, entities that left queries unanswered say how many.
    """
    # Log scales and limits before any data, so that autoscaling never runs:
    # its margins overflow for errors near the float range (ulps of a zero d*).
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_autoscale_on(False)
    speeds = [s.qps for s in stats.values() if math.isfinite(s.qps)]
    floor = FLOORS[unit]
    errors = [BOUNDS[unit][0]]
    errors += [
        e
        for s in stats.values()
        for e in (s.worst[unit], s.median[unit])
        if math.isfinite(e) and e <= CAP[unit]
    ]
    if not speeds:
        return {}, ""
    ax.set_xlim(min(speeds) / 3, max(speeds) * 3)
    low, high = math.log10(max(min(errors), floor)), math.log10(max(max(errors), floor))
    top = min(high + 0.08 * (high - low) + 0.5, math.log10(CAP[unit]))
    on_floor = any(
        min(s.worst[unit], s.median[unit]) <= floor
        for s in stats.values()
        if math.isfinite(s.qps) and not math.isnan(s.worst[unit])
    )
    bottom = math.log10(floor) - 0.3 if on_floor else low - 0.6
    ax.set_ylim(10.0**bottom, 10.0**top)
    _log_ticks(ax.yaxis, bottom, top, floor=floor if on_floor else None)
    handles, points, off_scale = {}, [], []
    for name, s in stats.items():
        colour, marker = style(name)
        x, worst, median = s.qps, s.worst[unit], s.median[unit]
        complete = s.failed == 0
        points.append((x, worst if complete else math.inf))
        if not math.isfinite(x) or math.isnan(worst):
            continue
        # Errors beyond the axis (past the float range, in ulps of a zero d*) sit on its top edge.
        shown = [min(max(v, floor), 10.0**top) for v in (median, worst)]
        ax.plot([x, x], shown, color=colour, lw=1, alpha=0.6, zorder=2)
        handles[name] = ax.scatter(
            x,
            shown[1],
            s=60,
            color=colour,
            marker=marker,
            zorder=3,
            edgecolors="black",
            lw=0.5,
            clip_on=False,
        )
        ax.scatter(
            x,
            shown[0],
            s=60,
            facecolors="white",
            edgecolors=colour,
            marker=marker,
            lw=1.5,
            zorder=3,
            clip_on=False,
        )
        if worst > 10.0**top:
            off_scale.append(worst)
        if failures and not complete:
            ax.annotate(
                f"{100 * s.failed / s.n:.2g}% failed",
                (x, shown[1]),
                xytext=(6, 4),
                textcoords="offset points",
                fontsize=8,
                color="firebrick",
            )
    note = ""
    if off_scale:
        most = max(off_scale)
        note = f"markers on the top edge: worst beyond {_short(10.0**top)}, up to " + (
            _short(most) if math.isfinite(most) else "past the float range"
        )
    bound, label = BOUNDS[unit]
    ax.axhline(bound, color="gray", ls=":", lw=1)
    if on_floor:
        ax.axhline(floor, color="lightgray", lw=0.8, zorder=1)
    ax.annotate(
        label,
        (1, bound),
        xycoords=("axes fraction", "data"),
        xytext=(-4, 3),
        textcoords="offset points",
        ha="right",
        fontsize=8,
        color="gray",
    )
    ax.grid(True, which="major", alpha=0.3)
    _draw_front(ax, [points[i] for i in summary.pareto(points)], floor)
    return handles, note


def _short(x):
    """``2.2e307`` for 2.2e+307: two digits, a short exponent."""
    return f"{x:.2g}".replace("e+", "e")


def _log_ticks(axis, low, high, most=8, floor=None):
    """Decade ticks between ``10**low`` and ``10**high``, at most ``most`` of them.

    Fixed ticks: matplotlib's log locator steps past the axis, and past the
    float range when the axis ends near it.  With ``floor``, where errors of
    0 are drawn, that tick reads "0 (≤ floor)" and the decades start above it.
    """
    from matplotlib.ticker import FixedLocator, FuncFormatter, NullLocator

    span = max(high - low, 1.0)
    step = next(k for k in (1, 2, 5, 10, 20, 25, 50, 100, 200) if span / k <= most)
    first = math.ceil(low / step) * step
    ticks = [10.0**k for k in range(first, math.floor(high) + 1, step)]
    if floor is not None:
        ticks = [floor] + [t for t in ticks if t >= floor * 10.0 ** max(step, 1)]

    def label(value, _position=None):
        if floor is not None and math.isclose(value, floor):
            return f"0 (≤{_short(floor)})"
        return f"$10^{{{round(math.log10(value))}}}$"

    axis.set_major_locator(FixedLocator(ticks))
    axis.set_major_formatter(FuncFormatter(label))
    if step > 1 or floor is not None:
        axis.set_minor_locator(NullLocator())


def _draw_front(ax, front, floor=FLOOR):
    """The Pareto front as the boundary of the region it dominates, which is shaded.

    ``front`` is sorted by speed; along it the error grows.  A point is
    dominated when it is left of and above a point of the front.
    """
    if not front:
        return
    (left, right), (bottom, top) = ax.get_xlim(), ax.get_ylim()
    xs, ys = [left], [max(front[0][1], floor)]
    for (x, y), following in zip(front, front[1:] + [(None, top)], strict=True):
        xs += [x, x]
        ys += [max(y, floor), max(following[1], floor)]
    ax.plot(xs, ys, color="black", ls="--", lw=1, zorder=1)
    ax.fill_between(xs, ys, top, color="gray", alpha=0.08, zorder=0, lw=0)
    ax.set_xlim(left, right)
    ax.set_ylim(bottom, top)


# -- 2. stability sweeps ------------------------------------------------------------------

#: Sweeps whose difficulty grows as the parameter shrinks: drawn with the
#: axis reversed, so that every sweep gets harder to the right.
SMALLER_IS_HARDER = {
    "near_surface",
    "sliver",
    "needle",
    "small",
    "disk_axis",
    "disk_rim",
    "pair_contact",
    "pair_near_parallel",
}


def _axis_values(name, members):
    """``(members, x positions, tick labels, scale note)`` of a sweep, harder to the right.

    Numeric sweeps are drawn at ``log10`` of their values (negated where a
    smaller value is harder) when those are evenly spread, else in order of
    difficulty at equal steps (``disk_axis`` runs 1e-8, 1e-16, 1e-100,
    1e-300, 0); categorical ones (``degenerate``) in registry order.
    """
    values = [f["difficulty"] for f in members]
    if any(v is None for v in values):
        labels = [str(next(iter(f["params"].values()))).replace("_", " ") for f in members]
        return members, list(range(len(members))), labels, ""
    sign = -1.0 if name in SMALLER_IS_HARDER else 1.0
    members = sorted(members, key=lambda f: sign * f["difficulty"])
    values = [f["difficulty"] for f in members]
    labels = []
    for v in values:
        exponent = round(math.log10(v)) if v > 0 else 0
        labels.append(
            "0" if v == 0 else f"$10^{{{exponent}}}$" if math.isclose(v, 10.0**exponent) else f"{v:g}"
        )
    if all(v > 0 for v in values):
        logs = [sign * math.log10(v) for v in values]
        steps = np.diff(logs)
        if len(steps) == 0 or steps.max() <= 3 * steps.min():
            return members, logs, labels, "log scale"
    return members, list(range(len(values))), labels, "log steps, not to scale"


def _floor_label(value, _position=None):
    """A decade tick's label; the floor, where errors of 0 are drawn, reads ``≤0.01``."""
    if math.isclose(value, FLOOR):
        return f"≤{FLOOR:g}"
    return f"$10^{{{round(math.log10(value))}}}$"


def _sweep_panel(ax_fail, ax, kind, name, members, unit="error_eps_s", bound=BOUND):
    """One sweep: the share of failed queries on ``ax_fail``, the worst error on ``ax``, with the
    dashed line at ``bound`` (eps·S)."""
    members, x, ticklabels, note = _axis_values(name, members)
    x = np.array(x, dtype=np.float64)
    worst_seen = bound
    any_failure = False
    for entity in members[0]["results"]:
        colour, marker = style(entity)
        stats = [summary.stats([f["results"][entity]]) for f in members]
        worst = np.array([s.worst[unit] for s in stats])
        failed = np.array([100.0 * s.failed / s.n for s in stats])
        answered = np.isfinite(worst)
        if answered.any():
            worst_seen = max(worst_seen, float(worst[answered].max()))
        # proximity's own methods on top: their errors are the small ones that others would hide.
        ax.plot(
            x[answered],
            _floor(worst[answered]),
            color=colour,
            marker=marker,
            ms=5,
            lw=1.3,
            label=entity,
            zorder=3 if entity in ("robust", "certified") else 2,
        )
        if failed.any():
            any_failure = True
            ax_fail.plot(x, failed, color=colour, marker=marker, ms=5, lw=1.3)
            # Where failures begin: each step of the sweep from none to some.
            for i in np.flatnonzero(failed > 0):
                neighbours = [j for j in (i - 1, i + 1) if 0 <= j < len(failed)]
                if any(failed[j] == 0 for j in neighbours):
                    ax.axvline(x[i], color=colour, ls=":", lw=1.2, alpha=0.8)
    ax.axhline(bound, color="gray", ls="--", lw=0.8)
    ax.set_yscale("log")
    ax.set_ylim(FLOOR / 2, max(worst_seen * 10, 1e2))
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    ax.yaxis.set_major_locator(LogLocator(base=10.0, numticks=8))
    ax.yaxis.set_major_formatter(FuncFormatter(_floor_label))
    ax.yaxis.set_minor_formatter(NullFormatter())
    ax.set_xticks(x, ticklabels, **({"fontsize": 7} if len(x) > 6 else {}))
    ax.grid(True, alpha=0.3)
    ax_fail.set_ylim(-8, 108)
    ax_fail.set_yticks([0, 50, 100])
    ax_fail.tick_params(labelbottom=False)
    ax_fail.grid(True, alpha=0.3)
    if not any_failure:
        ax_fail.text(
            0.5,
            0.5,
            "every query answered",
            transform=ax_fail.transAxes,
            ha="center",
            va="center",
            fontsize=8,
            color="dimgray",
        )
    pad = 0.4 * (x.max() - x.min()) / max(len(x) - 1, 1) if len(x) > 1 else 0.5
    ax.set_xlim(x.min() - pad, x.max() + pad)
    label = DIFFICULTY.get(name, name)
    ax.set_xlabel(f"{label} ({note})" if note else label, fontsize=8)
    title = name.removeprefix("disk_").removeprefix("pair_").replace("_", " ")
    ax_fail.set_title(f"{kind.replace('_', '–')}: {title}")


def stability(raw, path, kinds, title, bound=BOUND, by_sweep=False):
    """Every sweep of the given query types: worst error and failure share against difficulty.

    ``bound`` is robust's, in eps·S, drawn dashed; ``by_sweep`` puts one sweep per row, the
    query types across (the types' sweeps must then be the same), else the types in turn.
    """
    plt = _plt()
    panels = [(kind, name, members) for kind in kinds for name, members in summary.sweeps(raw, kind).items()]
    if by_sweep:
        order = list(dict.fromkeys(name for _, name, _ in panels))
        panels.sort(key=lambda panel: order.index(panel[1]))
    if not panels:
        return None
    ncols = len(kinds) if by_sweep else 3
    nrows = math.ceil(len(panels) / ncols)
    height = 3.6 * nrows + 1.7
    fig = plt.figure(figsize=(4.2 * ncols, height))
    outer = fig.add_gridspec(
        nrows,
        ncols,
        hspace=0.5,
        wspace=0.25,
        left=0.065,
        right=0.985,
        top=1 - 0.8 / height,
        bottom=1.45 / height,
    )
    handles = {}
    for i, (kind, name, members) in enumerate(panels):
        inner = outer[i // ncols, i % ncols].subgridspec(2, 1, height_ratios=(1, 3), hspace=0.08)
        ax_fail = fig.add_subplot(inner[0])
        ax = fig.add_subplot(inner[1], sharex=ax_fail)
        _sweep_panel(ax_fail, ax, kind, name, members, bound=bound)
        if i % ncols == 0:
            ax.set_ylabel("worst error (eps·S)")
            ax_fail.set_ylabel("failed %")
        for line in ax.get_lines():
            if not line.get_label().startswith("_"):
                handles.setdefault(line.get_label(), line)
    from matplotlib.lines import Line2D

    labels = list(handles) + [f"robust's bound, {bound:g} eps·S", "failures begin"]
    lines = list(handles.values()) + [
        Line2D([], [], color="gray", ls="--", lw=0.8),
        Line2D([], [], color="gray", ls=":", lw=1.2),
    ]
    fig.legend(
        lines,
        labels,
        loc="lower center",
        ncol=min(len(labels), 5),
        frameon=False,
        bbox_to_anchor=(0.5, 0.42 / height),
    )
    fig.suptitle(title, y=1 - 0.1 / height)
    fig.text(
        0.5,
        1 - 0.42 / height,
        _subtitle(raw)
        + f"  ·  harder to the right  ·  errors of {FLOOR:g} or less, 0 included, drawn at {FLOOR:g}",
        ha="center",
        fontsize=8,
        color="dimgray",
    )
    _caption(fig, Path(path).stem, y=0.1 / height)
    return _save(fig, path)


# -- 3. tessellation -------------------------------------------------------------------------


def tessellation(raw, path):
    """Error and time per query against the number of segments ``K``."""
    records = [r for r in raw.get("tessellation", []) if not r.get("skipped")]
    if not records:
        return None
    plt = _plt()
    fig, (ax_err, ax_time) = plt.subplots(1, 2, figsize=(13, 6.0))
    kind_style = {"disk": "-", "circle": "--"}
    curves = {}
    for r in records:
        if r["entity"] == "robust" or r["segments"] is None:
            continue
        curves.setdefault((r["entity"], r["kind"]), []).append(r)
    all_k = sorted({r["segments"] for rs in curves.values() for r in rs})
    skipped = {(r["entity"], r["kind"]) for r in raw.get("tessellation", []) if r.get("skipped")}
    for (name, kind), rs in curves.items():
        rs = sorted(rs, key=lambda r: r["segments"])
        colour, marker = style(name)
        k = np.array([r["segments"] for r in rs])
        worst = np.array([max((e for e in r["error"] if e is not None), default=math.nan) for r in rs])
        us = np.array([1e6 / r["timing"]["qps"] for r in rs])
        label = f"{name}, {kind}"
        if (name, kind) in skipped:
            label += f" (to K = {k[-1]}: time budget)"
        ax_err.plot(k, worst, color=colour, marker=marker, ls=kind_style[kind], label=label)
        ax_time.plot(k, us, color=colour, marker=marker, ls=kind_style[kind], label=label)
    if all_k:
        kk = np.geomspace(min(all_k), max(all_k), 200)
        s = np.sin(np.pi / (2 * kk))
        ax_err.plot(kk, 2 * s * s, color="black", lw=1, ls=":", label="sagitta R(1 − cos π/K)")
    for r in records:
        if r["entity"] == "robust":
            worst = max((e for e in r["error"] if e is not None), default=0.0)
            shown = f"{worst:.1e}" if worst > 0 else "0, drawn at 1e-17"
            ax_err.axhline(
                max(worst, 1e-17),
                color=style("robust")[0],
                lw=1.5,
                ls=kind_style[r["kind"]],
                label=f"proximity robust, {r['kind']}: worst error ({shown})",
            )
    for kind in ("disk", "circle"):
        family = next(
            (f for f in raw["families"] if f["kind"] == kind and f["name"] == "disk_well_conditioned"), None
        )
        timing = family and family["results"].get("robust", {}).get("timing")
        if timing:
            ax_time.axhline(
                1e6 / timing["qps"],
                color=style("robust")[0],
                lw=1.5,
                ls=kind_style[kind],
                label=f"proximity robust, {kind}: time per query in a batch",
            )
    for ax in (ax_err, ax_time):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.grid(True, which="major", alpha=0.3)
        ax.set_xlabel("segments K (log scale)")
    ax_err.set_ylabel("worst |d − d*| (R = 1, so in units of R)")
    ax_time.set_ylabel("time per query (µs)")
    ax_err.set_title("error against K (the libraries' lines lie on one another)")
    ax_time.set_title("time per query against K")
    # One legend per panel, under it: a line's label says which panel's quantity it is.
    for ax in (ax_err, ax_time):
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, frameon=False, fontsize=8)
    n = records[0]["n"]
    fig.suptitle(
        "Tessellated circles and disks: error and cost against the number of segments K "
        f"({n} queries, R = 1; solid: disk, dashed: circle)",
        y=0.99,
    )
    fig.text(0.5, 0.935, _subtitle(raw), ha="center", fontsize=8, color="dimgray")
    _caption(fig, "tessellation")
    # Fixed margins: tight_layout would shrink a panel to make room for the other's wider legend.
    fig.subplots_adjust(left=0.07, right=0.98, top=0.86, bottom=0.36, wspace=0.22)
    return _save(fig, path)


# -- 4. the mesh benchmark's libraries ------------------------------------------------------


def mesh_peers(raw, path):
    """Points per second (one thread) against the largest error relative to
    the mesh's size, per mesh and point set, from :func:`benchmarks.meshes.run_peers`'s data."""
    meshes = [(label, entry) for label, entry in raw["meshes"].items() if entry["peers"]]
    if not meshes:
        return None
    plt = _plt()
    sets = ("near", "box")
    fig, axes = plt.subplots(len(meshes), len(sets), figsize=(11, 3.3 * len(meshes) + 2.2), squeeze=False)
    floor = 1e-19
    handles = {}
    for row, (label, entry) in enumerate(meshes):
        for col, set_name in enumerate(sets):
            ax = axes[row, col]
            ax.set_xscale("log")
            ax.set_yscale("log")
            drawn = []
            for name, peer in entry["peers"].items():
                record = peer["runs"].get("1", {})
                timing = record.get("sets", {}).get(set_name, {}).get("unsigned")
                if not timing or "errors" not in timing:
                    continue
                errors = timing["errors"]
                relative = errors["max_error"] / entry["size"]
                x, y = timing["qps"], max(relative, floor) if math.isfinite(relative) else None
                if y is None:
                    continue
                colour, marker = PEER_STYLE.get(name, style(name))
                handles[peer["label"]] = ax.scatter(
                    x, y, s=60, color=colour, marker=marker, edgecolors="black", lw=0.5, zorder=3
                )
                drawn.append(y)
                if errors["off"]:
                    ax.annotate(
                        f"{errors['off']:,} of {errors['n']:,} off",
                        (x, y),
                        xytext=(6, 4),
                        textcoords="offset points",
                        fontsize=8,
                        color="firebrick",
                    )
            if not drawn:
                ax.set_visible(False)
                continue
            low = math.log10(min(drawn + [2.0**-53]))
            high = math.log10(max(drawn + [2.0**-24]))
            on_floor = min(drawn) <= floor
            bottom = math.log10(floor) - 0.5 if on_floor else low - 0.7
            ax.set_ylim(10.0**bottom, 10.0 ** (high + 0.8))
            _log_ticks(ax.yaxis, bottom, high + 0.8, floor=floor if on_floor else None)
            for value, text in ((2.0**-53, "float64 resolution, 1.1e-16"), (2.0**-24, "float32, 6e-8")):
                ax.axhline(value, color="gray", ls=":", lw=1)
                ax.annotate(text, (0.99, value), xycoords=("axes fraction", "data"), xytext=(0, 3),
                            textcoords="offset points", fontsize=7, color="gray", ha="right")  # fmt: skip
            left, right = ax.get_xlim()
            ax.set_xlim(left / 2, right * 2)
            ax.grid(True, which="major", alpha=0.3)
            ax.set_title(f"{label}: {set_name} points", fontsize=10)
            if col == 0:
                ax.set_ylabel("largest error / mesh size")
            if row == len(meshes) - 1:
                ax.set_xlabel("points per second, one thread (unsigned distance)")
    fig.legend(list(handles.values()), list(handles), loc="lower center", ncol=min(len(handles), 4),
               frameon=False, bbox_to_anchor=(0.5, 0.07))  # fmt: skip
    meta = raw["meta"]
    fig.suptitle("Meshes: accuracy against speed, proximity and the other libraries", y=0.995)
    fig.text(
        0.5,
        1 - 0.55 / fig.get_figheight(),
        f"{meta['command']}  ·  seed {meta['seed']}  ·  {meta['points']:,} points per set, errors over the "
        f"first {meta['exact_sample']}  ·  {meta['cpus']} cores  ·  errors of 0 drawn on the labelled floor",
        ha="center",
        fontsize=8,
        color="dimgray",
    )
    _caption(fig, "mesh_peers")
    fig.tight_layout(rect=(0, 1.9 / fig.get_figheight(), 1, 1 - 0.7 / fig.get_figheight()))
    return _save(fig, path)


def stability_pairs(raw, path):
    """The pair sweeps of :mod:`benchmarks.pair_stability`'s raw data, one row per sweep."""
    from proximity.testing.scenes import PAIRS

    with np.errstate(over="ignore"):
        return stability(
            raw,
            path,
            tuple(PAIRS),
            "Stability of the primitive pairs: worst error and failures along each sweep",
            bound=16.0,
            by_sweep=True,
        )


def draw_all(raw, out):
    """Draw every chart into directory ``out``; returns ``{name: path}`` of those drawn."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    # Log tick locators overflow, harmlessly, on axes that reach the float range.
    with np.errstate(over="ignore"):
        drawn = _draw_all(raw, out)
    return {name: path for name, path in drawn.items() if path is not None}


def _draw_all(raw, out):
    return {
        "accuracy_speed": accuracy_speed(raw, out / "accuracy_speed.png"),
        "stability_triangle": stability(
            raw,
            out / "stability_triangle.png",
            ("triangle",),
            "Stability of point–triangle queries: worst error and failures along each sweep",
        ),
        "stability_round": stability(
            raw,
            out / "stability_round.png",
            ("disk", "circle"),
            "Stability of point–disk and point–circle queries: worst error and failures along each sweep",
        ),
        "tessellation": tessellation(raw, out / "tessellation.png"),
    }
